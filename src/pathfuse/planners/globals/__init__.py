"""The global planners: a problem in, a path of waypoints in metres out."""
