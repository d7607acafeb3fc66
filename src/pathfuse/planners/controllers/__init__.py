"""The controllers: drive along a global path (or without one) to the goal."""
