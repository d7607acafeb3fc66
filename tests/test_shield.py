"""The safety shield (pathfuse.shield): the stop model against a brute-force simulation of the
unicycle, and the invariant that a shielded robot never touches the static map, whatever its
controller commands, checked by hypothesis against dense sampling that shares no code with
the simulator."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pathfuse.costmap import Discs, make_costmap
from pathfuse.planners.base import Controller
from pathfuse.planners.drive import admissible
from pathfuse.problem import Problem
from pathfuse.shield import (
    ASKED,
    EVADE,
    NEAREST,
    UNSAFE,
    holonomic_stop_clear,
    shield_holonomic,
    shield_unicycle,
    unicycle_stop_clear,
    unicycle_stop_disc_gap,
)
from pathfuse.world import World

# ----------------------------------------------------------------------------- brute force


def arc_points(x, y, th, v, w, dt, n=200):
    """Dense points of the arc of (v, w) over dt, in closed form (not pathfuse.sweep)."""
    t = np.linspace(0.0, dt, n + 1)
    if abs(w) < 1e-9:
        return x + v * t * math.cos(th), y + v * t * math.sin(th), th + w * dt
    r = v / w
    return (x + r * (np.sin(th + w * t) - math.sin(th)),
            y - r * (np.cos(th + w * t) - math.cos(th)), th + w * dt)


def point_clearance(occ, res, px, py):
    """Least distance from each point to an occupied square or the map's outside."""
    h, w = occ.shape
    px = np.atleast_1d(px)[:, None]
    py = np.atleast_1d(py)[:, None]
    edge = np.minimum.reduce([px[:, 0], w * res - px[:, 0], py[:, 0], h * res - py[:, 0]])
    rows, cols = np.nonzero(occ)
    if rows.size == 0:
        return edge
    x0, x1 = cols * res, (cols + 1) * res
    y0, y1 = rows * res, (rows + 1) * res
    dx = np.maximum(np.maximum(x0 - px, px - x1), 0.0)
    dy = np.maximum(np.maximum(y0 - py, py - y1), 0.0)
    return np.minimum(np.hypot(dx, dy).min(axis=1), edge)


def brute_stop(occ, res, x, y, th, v, w, dt, amax, alpha):
    """The command's tick and the braking stop, sampled densely: (least clearance, ticks)."""
    best = math.inf
    ticks = 0
    while True:
        xs, ys, th1 = arc_points(x, y, th, v, w, dt)
        best = min(best, float(point_clearance(occ, res, xs, ys).min()))
        ticks += 1
        if v == 0.0 or ticks > 10_000:
            return best, ticks
        x, y, th = float(xs[-1]), float(ys[-1]), th1
        v = max(v - amax * dt, 0.0) if v > 0 else min(v + amax * dt, 0.0)
        w = max(w - alpha * dt, 0.0) if w > 0 else min(w + alpha * dt, 0.0)


# ----------------------------------------------------------------------------- the stop


def _cm(occ, res=1.0, clear=0.3):
    """The costmap of a test map: radius and clearance ``clear``."""
    return make_costmap(occ, clear, resolution_m=res, clear_m=clear)


def _discs(pos, speed, radius):
    return Discs(pos, pos, speed, radius)


NONE = Discs(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0), np.zeros(0))


def test_unicycle_stop_agrees_with_brute_force():
    rng = np.random.default_rng(0)
    res = 0.25
    decided = 0
    for _ in range(300):
        occ = rng.random((16, 16)) < 0.12
        x, y = rng.uniform(0.5, 3.5, 2)
        th = rng.uniform(-math.pi, math.pi)
        v, w = rng.uniform(-1.0, 2.5), rng.uniform(-2.5, 2.5)
        dt, amax, alpha = rng.uniform(0.05, 0.3), rng.uniform(0.5, 4), rng.uniform(1, 8)
        clear = rng.uniform(0.05, 0.4)
        got = unicycle_stop_clear(_cm(occ, res, clear), x, y, th, v, w, dt, amax, alpha, clear)
        md, _ = brute_stop(occ, res, x, y, th, v, w, dt, amax, alpha)
        # dense sampling overestimates the least clearance by at most half a sample spacing
        slack = abs(v) * dt / 200
        if md < clear - 1e-9:
            assert not got, (x, y, th, v, w, md, clear)
            decided += 1
        elif md > clear + slack:
            assert got, (x, y, th, v, w, md, clear)
            decided += 1
    assert decided > 250


def test_the_stop_is_what_the_world_executes():
    """The stop's commands stay in the world's window (nothing is clipped) and the world's
    poses follow the closed-form arcs of the brute-force stop."""
    w = World({"map": {"rows": ["." * 40] * 40}, "start": [10.0, 10.0], "goal": [39.0, 39.0],
               "robot": {"model": "diff-drive", "radius": 0.2, "heading": 0.3,
                         "max_speed": 2.0, "max_accel": 1.5, "max_yaw_accel": 3.0},
               "dt": 0.1})
    obs = w.reset()
    for _ in range(15):  # speed up while turning
        obs, *_ = w.step((2.0, 1.4))
    v, om = (float(c) for c in obs.command)
    assert v > 1.4 and om > 1.0
    x, y, th = float(obs.position[0]), float(obs.position[1]), float(obs.heading)
    while v != 0.0:
        v = max(v - 1.5 * 0.1, 0.0)
        om = max(om - 3.0 * 0.1, 0.0)
        obs, term, trunc, info = w.step((v, om))
        assert not info["clipped"] and not term
        xs, ys, th = arc_points(x, y, th, v, om, 0.1)
        x, y = float(xs[-1]), float(ys[-1])
        assert obs.position.tolist() == pytest.approx([x, y], abs=1e-9)
        assert obs.heading == pytest.approx(th, abs=1e-12)


def test_a_straight_stop_can_clear_where_every_real_stop_hits():
    """The mechanism of the fusion's BARN collisions: drive.admissible approved a command
    because a straight stop on the final heading cleared, while the robot, whose yaw rate
    can only unwind at its limit, cannot stop without touching."""
    occ = np.zeros((40, 40), dtype=np.bool_)
    occ[20:, 20:] = True
    args = (1.0, 0.8, -2.711, 1.603, 1.845, 0.1)
    v = args[3]
    cm = _cm(occ, 0.1, 0.333)
    assert admissible(cm, *args, v * v / 4.0, 0.333)
    assert not unicycle_stop_clear(cm, *args, 2.0, 4.0, 0.333)
    md, _ = brute_stop(occ, 0.1, *args, 2.0, 4.0)
    assert md < 0.333


def test_holonomic_stop_without_acceleration_limit_is_the_tick_alone():
    occ = np.zeros((10, 10), dtype=np.bool_)
    occ[:, 6] = True
    # 1 m/s for 0.5 s from x = 5.1 ends at 5.6, 0.4 m from the wall: clear with radius 0.3
    assert holonomic_stop_clear(_cm(occ), 5.1, 5.0, 1.0, 0.0, 0.5, math.inf, 0.3)
    # with 1 m/s^2 it also brakes 0.25 m (0.5 m/s for one more tick): not clear
    assert not holonomic_stop_clear(_cm(occ), 5.1, 5.0, 1.0, 0.0, 0.5, 1.0, 0.3)


def test_shield_codes():
    occ = np.zeros((10, 10), dtype=np.bool_)
    occ[:, 6] = True
    lim = (0.0, 1.0, 1.0, 2.0, 4.0)
    v, w, code = shield_unicycle(_cm(occ), 2.0, 5.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.5,
                                 *lim, NONE, 0.0)
    assert (v, w, code) == (1.0, 0.0, ASKED)
    # facing the wall at full speed, 0.4 m from it: brake (and turn away)
    v, w, code = shield_unicycle(_cm(occ), 5.3, 5.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.5,
                                 *lim, NONE, 0.0)
    assert code == NEAREST and v < 1.0
    assert unicycle_stop_clear(_cm(occ), 5.3, 5.0, 0.0, v, w, 0.5, 1.0, 4.0, 0.3)
    # too close already: no clear command exists; the emergency stop is returned
    v, w, code = shield_unicycle(_cm(occ), 5.5, 5.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.5,
                                 *lim, NONE, 0.0)
    assert code == UNSAFE and v == 0.5
    # a disc 2 m ahead that may come at 1 m/s: going on at 1 m/s, the robot could not stop
    # before the disc can reach it; the shield brakes and turns away until it can
    dp, ds, dr = np.array([[4.0, 5.0]]), np.array([1.0]), np.array([0.3])
    gap = unicycle_stop_disc_gap(2.0, 5.0, 0.0, 1.0, 0.0, 0.5, 1.0, 4.0, 0.3, _discs(dp, ds, dr))
    assert gap < 0
    v, w, code = shield_unicycle(_cm(occ), 2.0, 5.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.5,
                                 *lim, _discs(dp, ds, dr), 0.0)
    assert code == NEAREST and v < 1.0 and w != 0.0
    assert unicycle_stop_disc_gap(2.0, 5.0, 0.0, v, w, 0.5, 1.0, 4.0, 0.3, _discs(dp, ds, dr)) >= 0
    # 1.2 m ahead no stop can keep clear of where it may be: the largest gap (evade)
    v, w, code = shield_unicycle(_cm(occ), 2.0, 5.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.5,
                                 *lim, _discs(dp - [0.8, 0.0], ds, dr), 0.0)
    assert code == EVADE and v == 0.5
    # far enough away, the asked command passes
    v, w, code = shield_unicycle(_cm(occ), 2.0, 5.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.5,
                                 *lim, _discs(dp + [0.0, 3.0], ds, dr), 0.0)
    assert code == ASKED
    ux, uy, code = shield_holonomic(_cm(occ), 5.5, 5.0, 0.0, 0.0, 1.0, 0.0, 0.5, 1.0,
                                    math.inf, NONE, 0.0)
    assert code == NEAREST and 5.5 + ux * 0.5 + 0.3 <= 6.0


# ----------------------------------------------------------------------------- the invariant


class Adversary(Controller):
    """Commands chosen to hit things: full speed at random yaw rates, towards the nearest
    occupied square, or anything in the limits; seeded."""

    native_unicycle = True

    def __init__(self, problem, seed, **kw):
        super().__init__(problem, None, None, **kw)
        self.rng = np.random.default_rng(seed)
        rows, cols = np.nonzero(problem.grid.occupied)
        res = problem.grid.resolution
        self.targets = np.column_stack([(cols + 0.5) * res, (rows + 0.5) * res])

    def act(self, obs):
        rb = self.problem.robot
        r = self.rng.random()
        if rb.is_diff_drive:
            top = rb.max_speed_mps
            if r < 0.4 and len(self.targets):
                d = self.targets - obs.position
                k = int(np.argmin(np.hypot(d[:, 0], d[:, 1])))
                err = math.atan2(d[k, 1], d[k, 0]) - obs.heading
                err = (err + math.pi) % (2 * math.pi) - math.pi
                return np.array([top, 10.0 * err])
            if r < 0.7:
                return np.array([top, self.rng.uniform(-1, 1) * rb.max_yaw_rate_radps])
            return np.array([self.rng.uniform(rb.min_speed_mps, top),
                             self.rng.uniform(-1, 1) * rb.max_yaw_rate_radps])
        a = self.rng.uniform(-math.pi, math.pi)
        if r < 0.4 and len(self.targets):
            d = self.targets - obs.position
            k = int(np.argmin(np.hypot(d[:, 0], d[:, 1])))
            a = math.atan2(d[k, 1], d[k, 0])
        s = rb.max_speed_mps * (1.0 if r < 0.7 else self.rng.random())
        return np.array([s * math.cos(a), s * math.sin(a)])


def _episode(seed, diff, shield, n_ticks=80):
    rng = np.random.default_rng(seed)
    res = float(rng.choice([0.1, 0.25, 0.5]))
    n = 14
    occ = rng.random((n, n)) < rng.uniform(0.05, 0.3)
    radius = float(rng.uniform(0.05, 1.5 * res))
    xs = (np.arange(n) + 0.5) * res
    free = [(x, y) for y in xs for x in xs
            if point_clearance(occ, res, x, y)[0] > radius + 0.01]
    if len(free) < 2:
        return None
    i, j = rng.choice(len(free), 2, replace=False)
    (sx, sy), (gx, gy) = free[i], free[j]
    robot = {"model": "diff-drive" if diff else "holonomic", "radius": radius,
             "max_speed": float(rng.uniform(0.3, 3.0)), "heading": float(rng.uniform(-3, 3)),
             "max_accel": float(rng.uniform(0.3, 5.0)), "shield": shield}
    if diff:
        robot.update(max_yaw_rate=float(rng.uniform(0.3, 4.0)),
                     max_yaw_accel=float(rng.uniform(0.5, 10.0)),
                     min_speed=float(rng.choice([0.0, -0.5])))
    elif rng.random() < 0.3:
        robot.pop("max_accel")  # changes velocity at once
    rows = ["".join("#" if occ[r, c] else "." for c in range(n)) for r in range(n - 1, -1, -1)]
    sc = {"map": {"rows": rows, "resolution": res}, "start": [sx, sy],
          "goal": [gx, gy], "goal_tolerance": 1e-9, "robot": robot,
          "dt": float(rng.uniform(0.05, 0.3)), "time_limit": 1000}
    world = World(sc)
    obs = world.reset()
    model = world.robot
    problem = Problem.create(world.scenario.grid, (sx, sy), (gx, gy), radius, robot=model)
    ctrl = Adversary(problem, seed, dt=world.dt, max_speed=model.max_speed_mps)
    worst = math.inf
    for _ in range(n_ticks):
        x, y, th = float(obs.position[0]), float(obs.position[1]), float(obs.heading)
        obs, term, trunc, info = world.step(ctrl.command(obs))
        c = obs.command
        if diff:
            px, py, _ = arc_points(x, y, th, float(c[0]), float(c[1]), world.dt)
        else:
            t = np.linspace(0.0, world.dt, 201)
            px, py = x + c[0] * t, y + c[1] * t
        worst = min(worst, float(point_clearance(occ, res, px, py).min()) - radius)
        if term:
            assert info["event"] == "reached" or not shield, (seed, info)
            break
    return worst, ctrl


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), diff=st.booleans())
def test_a_shielded_robot_never_touches_the_static_map(seed, diff):
    out = _episode(seed, diff, shield=True)
    if out is None:
        return
    worst, ctrl = out
    assert worst >= -1e-9, (seed, diff, worst)
    assert ctrl.shield_counts[UNSAFE] == 0


def test_the_adversary_does_collide_without_the_shield():
    """The property above can fail: the same adversary, unshielded, hits the map."""
    hits = 0
    for seed in range(40):
        for diff in (True, False):
            out = _episode(seed, diff, shield=False)
            if out is not None and out[0] < -1e-6:
                hits += 1
    assert hits >= 20


def _crowd_episode(seed, diff, shield=True, n_ticks=120):
    """An open hall with random walkers that may turn anywhere at any tick, an adversarial
    controller, every disc sensed."""
    rng = np.random.default_rng(seed)
    robot = {"model": "diff-drive" if diff else "holonomic", "radius": 0.25,
             "max_speed": float(rng.uniform(0.5, 2.0)), "max_accel": float(rng.uniform(0.5, 3)),
             "sensing_radius": 100.0, "shield": shield}
    if diff:
        robot.update(max_yaw_rate=2.0, max_yaw_accel=4.0)
    obstacles = []
    start = np.array([6.0, 6.0])
    while len(obstacles) < int(rng.integers(2, 7)):
        p = rng.uniform(0.6, 11.4, 2)
        r = float(rng.uniform(0.2, 0.5))
        if np.hypot(*(p - start)) < 0.25 + r + 0.3:
            continue
        obstacles.append({"random_walk": {"position": p.tolist(),
                                          "speed": float(rng.uniform(0.2, 1.5)),
                                          "seed": int(rng.integers(1 << 30)),
                                          "turn_std": float(rng.uniform(0.5, 6.0))},
                          "radius": r})
    sc = {"map": {"rows": ["." * 12] * 12}, "start": start.tolist(), "goal": [11.5, 11.5],
          "goal_tolerance": 1e-9, "robot": robot, "dt": 0.1, "time_limit": 1000,
          "obstacles": obstacles}
    world = World(sc)
    obs = world.reset(seed)
    problem = Problem.create(world.scenario.grid, tuple(start), (11.5, 11.5), 0.25,
                             robot=world.robot)
    ctrl = Adversary(problem, seed, dt=world.dt, max_speed=world.robot.max_speed_mps)
    for _ in range(n_ticks):
        if len(obs.obstacles) and rng.random() < 0.5:  # chase the nearest walker
            d = obs.obstacles.positions - obs.position
            k = int(np.argmin(np.hypot(d[:, 0], d[:, 1])))
            ctrl.targets = obs.obstacles.positions[k:k + 1]
        obs, term, trunc, info = world.step(ctrl.command(obs))
        if term:
            return info
    return None


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), diff=st.booleans())
def test_passive_safety_among_walkers_that_turn_anywhere(seed, diff):
    """Walkers keep their speed but may turn at any tick; the shielded robot may be walked
    into, but it is never moving when a contact happens."""
    info = _crowd_episode(seed, diff)
    if info is not None and info["event"] == "collision":
        assert info["at_fault"] is False, (seed, diff, info)


def test_the_walker_chase_is_the_robots_fault_without_the_shield():
    faults = sum(1 for seed in range(30) for diff in (True, False)
                 if (info := _crowd_episode(seed, diff, shield=False)) is not None
                 and info["at_fault"])
    assert faults >= 20
