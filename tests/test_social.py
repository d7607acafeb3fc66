"""Social behaviour among moving discs (ours; pathfuse.planners.controllers.social):
personal space over the predicted gaps and a committed passing side, in dwa, the fusion's
window and mppi."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pathfuse.grid import GridMap
from pathfuse.planners.controllers import dwa_kernel as K
from pathfuse.planners.controllers.fusion_window import ForceWindow
from pathfuse.planners.controllers.social import COMMIT_M, PassingSides
from pathfuse.planners.params import SocialParams
from pathfuse.problem import Problem
from pathfuse.robot import RobotModel
from pathfuse.sweep import disc_sweep_gaps
from pathfuse.world import simulate

HALL = GridMap.from_rows(["." * 16] * 6)  # 16 m x 6 m, empty
PTS = np.array([[1.0, 3.0], [15.0, 3.0]])
CUM = np.array([0.0, 14.0])


def _settings(**social):
    pb = Problem.create(HALL, (1.0, 3.0), (15.0, 3.0), 0.2,
                        robot=RobotModel.diff_drive(radius_m=0.2))
    fw = ForceWindow(pb, 0.1, social=SocialParams(**social))
    return fw.costmap, fw.f


def _choose(f, disc_y, dside=0.0):
    dpos = np.array([[7.0, disc_y]])
    dvel = np.array([[-0.6, 0.0]])
    drad = np.array([0.3])
    chosen = np.zeros((1, 2))
    cm, s = f
    tick = K.DwaTick(np.inf, 1.0, 0.0)  # the route along +x
    a0, a1, count, _ = K.dwa_choose(cm, s, tick, 4.0, 3.0, 0.0, 0.8, 0.0, PTS, CUM, 0,
                                    dpos, dvel, drad, np.array([dside]), chosen)
    assert count > 0
    return a0, a1, chosen[0]


def _brute_gap(v, w, disc_y, horizon=2.5, h=0.01):
    """The least gap of a constant (v, w) rollout from (4, 3, 0) to the disc walking at
    -0.6 m/s from (7, disc_y), by small steps (independent of the kernel)."""
    x, y, th = 4.0, 3.0, 0.0
    best = np.inf
    for i in range(int(horizon / h)):
        t = i * h
        q = np.array([[7.0 - 0.6 * t, disc_y]])
        q1 = np.array([[7.0 - 0.6 * (t + h), disc_y]])
        nx = x + v * np.cos(th) * h
        ny = y + v * np.sin(th) * h
        best = min(best, disc_sweep_gaps(np.array([x, y]), np.array([nx, ny]), 0.2, q, q1,
                                         np.array([0.3]))[0])
        x, y, th = nx, ny, th + w * h
    return best


def test_personal_space_widens_the_predicted_pass():
    off = _choose(_settings(social=False), 3.1)
    on = _choose(_settings(), 3.1)
    g_off = _brute_gap(off[0], off[1], 3.1)
    g_on = _brute_gap(on[0], on[1], 3.1)
    assert g_on > g_off + 0.02  # one tick's window turns the robot only a little
    # the kernel's predicted gap of the chosen sample agrees with the brute-force rollout
    assert on[2][1] == pytest.approx(g_on, abs=0.03)


def test_a_committed_side_is_kept():
    # a disc walking dead ahead along the route: either side will do, the committed one wins
    f = _settings()
    for side in (1.0, -1.0):
        assert _choose(f, 3.0, dside=side)[2][0] == side
    # without the critic the commitment has no effect
    f0 = _settings(side_weight=0.0)
    assert _choose(f0, 3.0, dside=1.0)[2][0] == _choose(f0, 3.0, dside=-1.0)[2][0]


def test_passing_sides_commit_and_release():
    ps = PassingSides(personal_m=0.5)
    ids = np.array([3, 8])
    dpos = np.array([[5.0, 3.2], [9.0, 2.0]])
    drad = np.array([0.3, 0.3])
    # disc 3 comes close on the left: committed; disc 8 too far to be an encounter
    chosen = np.array([[1.0, 0.2], [-1.0, 0.5 + COMMIT_M + 0.1]])
    ps.update(ids, chosen, dpos, (4.0, 3.0), (1.0, 0.0), drad, 0.2)
    assert ps.sides(ids).tolist() == [1.0, 0.0]
    # a later tick whose best sample would pass on the other side does not change it
    ps.update(ids, np.array([[-1.0, 0.1], [0.0, np.inf]]), dpos, (4.2, 3.0), (1.0, 0.0),
              drad, 0.2)
    assert ps.sides(ids).tolist() == [1.0, 0.0]
    # disc 3 falls behind the robot: released; an unsensed disc is forgotten
    ps.update(ids[:1], np.array([[1.0, 0.4]]), np.array([[3.0, 3.2]]), (4.0, 3.0), (1.0, 0.0),
              drad[:1], 0.2)
    assert ps.committed == {}


HEAD_ON = Path(__file__).resolve().parents[1] / "examples" / "scenarios" / "head_on.yaml"


@pytest.mark.parametrize("planner", ["dwa", "fusion"])
def test_a_head_on_disc_is_passed_with_personal_space(planner):
    # head_on.yaml: a 5 m wide hall, a disc walking head on (perturbed by the seed)
    gaps = {soc: [simulate(HEAD_ON, planner={"name": planner, "params": {"social": soc}},
                           seed=s, robot={"model": "diff-drive"}) for s in range(4)]
            for soc in (True, False)}
    for ep in gaps[True]:
        assert ep.status.name == "SUCCESS"
        assert ep.min_obstacle_distance_m >= 0.3
    assert min(ep.min_obstacle_distance_m for ep in gaps[False]) < 0.3


def test_switch_off_is_the_planner_without_the_critics():
    sc = {"map": {"rows": ["." * 16] * 6}, "start": [1.0, 3.0], "goal": [15.0, 3.0],
          "robot": {"radius": 0.2, "model": "diff-drive"},
          "obstacles": [{"position": [9.0, 3.1], "velocity": [-0.6, 0.0], "radius": 0.3}]}
    # (the fusion's social: false also drops the meeting points of its local path)
    for name in ("dwa", "mppi"):
        a = simulate(sc, planner={"name": name, "params": {"social": False}})
        b = simulate(sc, planner={"name": name, "params": {"social_weight": 0.0,
                                                           "social_replan": False,
                                                           **({} if name == "mppi" else
                                                              {"side_weight": 0.0,
                                                               "dwell_s": 0.0})}})
        np.testing.assert_array_equal(a.positions, b.positions)


def _brute_dwell(px, py, t, q, v, rd, radius, dwell_s, personal, n=20001):
    """The dwell critic by sampling the disc's lane finely (independent of the kernel)."""
    u = np.linspace(0.0, 1.0, n)
    worst = 0.0
    for i in range(rd.shape[0]):
        xs = q[i, 0] + v[i, 0] * (t + u * dwell_s)
        ys = q[i, 1] + v[i, 1] * (t + u * dwell_s)
        d = np.hypot(xs - px, ys - py)
        k = int(np.argmin(d))
        g = d[k] - radius - rd[i]
        if g < personal:
            worst = max(worst, (personal - max(g, 0.0)) / personal * (1.0 - 0.5 * u[k]))
    return worst


def test_dwell_shortfall_matches_a_sampled_lane():
    from pathfuse.planners.controllers.social import dwell_shortfall

    rng = np.random.default_rng(7)
    hits = 0
    for _ in range(300):
        n = int(rng.integers(1, 4))
        q = rng.uniform(-3, 3, (n, 2))
        v = rng.uniform(-1.5, 1.5, (n, 2))
        rd = rng.uniform(0.1, 0.4, n)
        px, py = rng.uniform(-2, 2, 2)
        t, dwell = float(rng.uniform(0, 2)), float(rng.uniform(0.2, 3))
        got = dwell_shortfall(px, py, t, q, v, rd, 0.25, dwell, 0.5, np.zeros(0, dtype=bool))
        want = _brute_dwell(px, py, t, q, v, rd, 0.25, dwell, 0.5)
        assert got == pytest.approx(want, abs=2e-3)
        hits += got > 0
    assert 30 < hits < 270  # both kinds of case were drawn


def test_dwell_critic_is_switchable_on_in_dwa_and_the_fusion_off_in_mppi():
    from pathfuse.planners.registry import get_planner

    assert get_planner("fusion").defaults()["dwell_s"] == 1.5
    assert get_planner("dwa").defaults()["dwell_s"] == 1.5  # since dwa among people
    assert get_planner("dwa").defaults()["dwell_steady"] is False
    assert get_planner("mppi").defaults()["dwell_s"] == 0.0
    _, s = _settings()
    assert s.dwell_s == 0.0  # SocialParams' own default (off)
    _, s = _settings(dwell_s=2.0)
    assert (s.dwell_s, s.dwell_weight) == (2.0, 50.0)
    assert _settings(dwell_s=2.0, social=False)[1].dwell_s == 0.0


def test_dwell_critic_moves_dwa_out_of_a_walkers_lane():
    """A walker far down a lane that crosses the route 2 m ahead reaches the route only
    after the rollouts' horizon: without the dwell critic dwa drives on into the lane at
    full speed, with it dwa slows so as not to end there."""
    dpos = np.array([[6.0, -2.0]])
    dvel = np.array([[0.0, 1.0]])   # up the lane x = 6, reaching the route (y = 3) in 5 s
    drad = np.array([0.3])

    def speed(**social):
        cm, s = _settings(**social)
        chosen = np.zeros((1, 2))
        tick = K.DwaTick(np.inf, 1.0, 0.0)  # the route along +x
        a0, a1, count, _ = K.dwa_choose(cm, s, tick, 4.0, 3.0, 0.0, 0.8, 0.0, PTS, CUM, 0,
                                        dpos, dvel, drad, np.array([0.0]), chosen)
        assert count > 0
        return a0

    v_off, v_on = speed(dwell_s=0.0), speed(dwell_s=3.0)
    assert v_off == pytest.approx(1.0)
    assert v_on < 0.8


def test_steady_discs_tell_walkers_from_wanderers():
    """The dwell critic counts a disc only once it has kept its velocity for a second: a
    disc on a straight leg is steady after that, one whose heading random-walks (pathfuse's
    random walkers: 1 rad/sqrt(s)) seldom is, a disc at rest always is."""
    from pathfuse.planners.controllers.social import STEADY_S, SteadyDiscs

    dt = 0.1
    rng = np.random.default_rng(0)
    sd = SteadyDiscs(dt)
    ids = np.array([0, 1, 2])
    heading = 0.0
    steady = []
    n_warm = int(round(STEADY_S / dt))
    for t in range(400):
        heading += rng.normal(0.0, 1.0 * np.sqrt(dt))
        dvel = np.array([[0.8, 0.0], [0.6 * np.cos(heading), 0.6 * np.sin(heading)],
                         [0.0, 0.0]])
        m = sd.update(ids, dvel)
        if t < n_warm:
            assert not m.any()  # not sensed long enough yet
        else:
            steady.append(m.copy())
    steady = np.array(steady)
    assert steady[:, 0].all() and steady[:, 2].all()
    assert steady[:, 1].mean() < 0.3
    # a disc no longer sensed is forgotten: back, it must be steady for a second again
    sd.update(np.array([0]), np.array([[0.8, 0.0]]))
    assert not sd.update(np.array([1]), np.array([[0.6, 0.0]]))[0]
