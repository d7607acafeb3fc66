"""The dynamic benchmark: episodes, counts, rates and intervals, files, determinism."""

import csv
import math
import statistics

import pytest
from PIL import Image
from scipy import stats as sps

from pathfuse.result import ConfigError
from pathfuse.studies.dynamic import (
    OUTCOMES,
    DynamicConfig,
    run_dynamic,
    summary_rows,
    write_dynamic_outputs,
)
from pathfuse.world import simulate
from pathfuse.world.generate import generate_scenarios

CFG = DynamicConfig(n_seeds=5, moving=(0, 3), speed_range=(0.4, 0.9),
                    planners=("fusion", "astar-follow", "astar-replan"), seed=11)
TIMING = {"mean_plan_time_s", "max_plan_time_s", "setup_time_s", "wall_s"}


@pytest.fixture(scope="module")
def run():
    return run_dynamic(CFG)


@pytest.fixture(scope="module")
def files(run, tmp_path_factory):
    return write_dynamic_outputs(run, tmp_path_factory.mktemp("dyn") / "out")


def read_csv(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def wilson(k, n, z=1.959963984540054):
    """Wilson score interval written out independently of pathfuse.stats."""
    p = k / n
    centre = (2 * k + z * z) / (2 * (n + z * z))
    half = z * math.sqrt(n * p * (1 - p) + z * z / 4) / (n + z * z)
    return p, max(0.0, centre - half), min(1.0, centre + half)


def test_every_episode_is_recorded_once(run):
    keys = [(r["moving"], r["index"], r["planner"]) for r in run.records]
    assert len(keys) == len(set(keys)) == CFG.n_episodes == 5 * 2 * 3
    assert {k[0] for k in keys} == {0, 3} and {k[1] for k in keys} == set(range(5))
    assert {r["status"] for r in run.records} <= set(OUTCOMES)


def test_records_are_the_episodes_of_pathfuse_simulate(run):
    # regenerate the family independently and replay a few episodes directly
    for k in CFG.moving:
        scs = generate_scenarios(CFG.n_seeds, moving=k, speed_range=CFG.speed_range,
                                 seed=CFG.seed)
        assert all(len(sc.obstacles) == k for sc in scs)
        for i in (0, CFG.n_seeds - 1):
            for name in CFG.planners:
                rec = next(r for r in run.records
                           if (r["moving"], r["index"], r["planner"]) == (k, i, name))
                ep = simulate(scs[i], planner=name)
                assert rec["status"] == ep.status.name
                assert rec["path_length_m"] == ep.path_length_m
                assert rec["n_ticks"] == ep.n_ticks
                assert rec["map"] == scs[i].grid.name
                assert rec["reached"] == (ep.status.name == "SUCCESS")
                assert (rec["time_to_goal_s"] is None) == (ep.time_to_goal_s is None)


def test_a_study_episode_replays_alone_with_the_run_seed():
    # the study gives a planner with a `seed` parameter the run's seed (MPPI's sampling,
    # and so the fusion's among discs on a diff-drive robot); simulate() with that seed,
    # in this process after other episodes, is the study's episode tick for tick
    cfg = DynamicConfig(n_seeds=2, moving=(2,), planners=("fusion",), seed=1,
                        robot={"model": "diff-drive"})
    recs = run_dynamic(cfg).records
    scs = generate_scenarios(2, moving=2, speed_range=cfg.speed_range, seed=1,
                             name="dyn-k2", robot={"model": "diff-drive"})
    for i in (1, 0):
        rec = next(r for r in recs if r["index"] == i)
        ep = simulate(scs[i], planner={"name": "fusion", "params": {"seed": i}})
        assert (rec["status"], rec["n_ticks"], rec["path_length_m"]) == \
            (ep.status.name, ep.n_ticks, ep.path_length_m)


def test_counts_add_up(run):
    rows = summary_rows(run)
    assert len(rows) == len(CFG.moving) * len(CFG.planners)
    for r in rows:
        assert r["episodes"] == CFG.n_seeds
        assert sum(r[k] for k in ("reached", "collision", "timeout", "local_minimum",
                                  "no_path")) == r["episodes"]


def test_summary_csv_agrees_with_an_independent_computation(files):
    eps = read_csv(files["episodes_csv"])
    summ = read_csv(files["summary_csv"])
    assert len(eps) == CFG.n_episodes
    assert len(summ) == len(CFG.moving) * len(CFG.planners)
    names = {"SUCCESS": "reached", "COLLISION": "collision", "TIMEOUT": "timeout",
             "LOCAL_MINIMUM": "local_minimum", "NO_PATH": "no_path"}
    for row in summ:
        mine = [e for e in eps if e["moving"] == row["moving"] and e["planner"] == row["planner"]]
        n = len(mine)
        assert int(row["episodes"]) == n == CFG.n_seeds
        total = 0
        for status, key in names.items():
            k = sum(e["status"] == status for e in mine)
            total += k
            assert int(row[key]) == k
            p, lo, hi = wilson(k, n)
            assert float(row[f"{key}_rate"]) == pytest.approx(p, abs=1e-12)
            assert float(row[f"{key}_ci_low"]) == pytest.approx(lo, abs=1e-9)
            assert float(row[f"{key}_ci_high"]) == pytest.approx(hi, abs=1e-9)
        assert total == n
        ok = [e for e in mine if e["status"] == "SUCCESS"]
        # a social success: reached and never within 0.3 m of a disc (no disc: inf gap)
        k = sum(float(e["min_obstacle_distance_m"] or "inf") >= 0.3 for e in ok)
        assert int(row["social"]) == k
        assert float(row["social_rate"]) == pytest.approx(wilson(k, n)[0], abs=1e-12)
        for col, label, unit in (("path_length_m", "path_length", "m"),
                                 ("time_to_goal_s", "time_to_goal", "s")):
            vals = [float(e[col]) for e in ok]
            if not vals:
                assert row[f"{label}_mean_{unit}"] == ""
                continue
            m = statistics.fmean(vals)
            assert float(row[f"{label}_mean_{unit}"]) == pytest.approx(m, rel=1e-12)
            assert float(row[f"{label}_median_{unit}"]) == pytest.approx(
                statistics.median(vals), rel=1e-12)
            lo, hi = float(row[f"{label}_ci_low_{unit}"]), float(row[f"{label}_ci_high_{unit}"])
            if label == "time_to_goal":  # percentile bootstrap: within the data, around the mean
                assert min(vals) <= lo <= m <= hi <= max(vals)
            elif len(vals) > 1:
                t_lo, t_hi = sps.t.interval(0.95, len(vals) - 1, loc=m, scale=sps.sem(vals))
                assert lo == pytest.approx(t_lo, rel=1e-9)
                assert hi == pytest.approx(t_hi, rel=1e-9)
        # episodes that did not reach the goal have no time to goal
        assert all((e["time_to_goal_s"] == "") == (e["status"] != "SUCCESS") for e in mine)


def test_time_to_goal_interval_stays_within_the_data_as_the_report_says():
    """A skewed sample (nine quick episodes, one slow): its Student-t interval would reach
    below zero; the report's footnote promises an interval within the data."""
    from pathfuse.studies.dynamic import DynamicRun, markdown_report

    cfg = DynamicConfig(n_seeds=10, moving=(0,), planners=("fusion",))
    times = [10.0] * 9 + [400.0]
    recs = [{"moving": 0, "index": i, "planner": "fusion", "status": "SUCCESS",
             "reached": True, "path_length_m": 14.0 + 0.1 * i, "time_to_goal_s": t,
             "mean_plan_time_s": 1e-4, "collision_at_fault": None,
             "min_static_clearance_m": 0.5, "min_obstacle_distance_m": math.inf}
            for i, t in enumerate(times)]
    t_lo = sps.t.interval(0.95, 9, loc=statistics.fmean(times), scale=sps.sem(times))[0]
    assert t_lo < 0  # what the report used to print
    (row,) = summary_rows(DynamicRun(cfg, recs, wall_s=1.0))
    lo, hi = row["time_to_goal_ci_low_s"], row["time_to_goal_ci_high_s"]
    assert min(times) <= lo < row["time_to_goal_mean_s"] == 49.0 < hi <= max(times)
    md = markdown_report(DynamicRun(cfg, recs, wall_s=1.0))
    assert f"| 49.00 [{lo:.2f}, {hi:.2f}] | 10.00 |" in md
    assert "stays within the range of the data" in md


def test_report_and_figure(files, run):
    md = files["report_md"].read_text(encoding="utf-8")
    assert "episodes/s" in md and f"{len(run.records)} episodes" in md
    for name in CFG.planners:
        assert f"| {name} |" in md
    for r in summary_rows(run):
        assert f"| {r['moving']} | {r['planner']} | {r['reached']}/{r['episodes']} = " in md
    im = Image.open(files["success_png"])
    assert im.format == "PNG" and im.size[0] > 300


def test_deterministic_and_independent_of_workers(run):
    again = run_dynamic(CFG, workers=2)
    assert again.workers == 2
    strip = [{k: v for k, v in r.items() if k not in TIMING} for r in run.records]
    assert strip == [{k: v for k, v in r.items() if k not in TIMING} for r in again.records]


def test_parameters_reach_the_planner():
    base = DynamicConfig(n_seeds=3, moving=(2,), planners=("fusion",), seed=4)
    tuned = DynamicConfig(n_seeds=3, moving=(2,), planners=("fusion",), seed=4,
                          params={"fusion": {"escape": False, "swerve": 0.0}})
    a, b = run_dynamic(base), run_dynamic(tuned)
    scs = generate_scenarios(3, moving=2, speed_range=base.speed_range, seed=4)
    for rec, sc in zip(b.records, scs, strict=True):
        ep = simulate(sc, planner={"name": "fusion", "params": {"escape": False,
                                                                 "swerve": 0.0}})
        assert (rec["status"], rec["path_length_m"]) == (ep.status.name, ep.path_length_m)
    assert [r["path_length_m"] for r in a.records] != [r["path_length_m"] for r in b.records]


def test_default_is_every_online_planner():
    from pathfuse.planners.registry import REGISTRY, planner_names

    def online_planner_names():
        return [n for n in planner_names() if REGISTRY[n].online]

    assert DynamicConfig().planners == tuple(online_planner_names())


@pytest.mark.parametrize("kw,fragment", [
    ({"n_seeds": 0}, "n_seeds"),
    ({"seed": -1}, "seed"),
    ({"moving": ()}, "moving"),
    ({"moving": (2, -1)}, "moving"),
    ({"moving": (1.5,)}, "moving"),
    ({"speed_range": (0.0, 0.5)}, "speed_range"),
    ({"speed_range": (0.9, 0.5)}, "speed_range"),
    ({"speed_range": ("fast", 1)}, "speed_range"),
    ({"speed_range": (0.5,)}, "speed_range"),
    ({"planners": ("fusion", "nope")}, "planners: unknown planner 'nope'"),
    ({"planners": "fusion"}, "planners"),
    ({"planners": ("fusion",), "params": {"apf": {}}}, "params.apf"),
    ({"params": {"fusion": {"kat": 1}}}, "params.fusion.kat"),
    ({"params": {"fusion": 3}}, "params.fusion"),
])
def test_bad_config_names_the_key(kw, fragment):
    with pytest.raises(ConfigError, match=None) as exc:
        DynamicConfig(**kw)
    assert fragment in str(exc.value)


def test_bad_workers():
    with pytest.raises(ConfigError, match="workers"):
        run_dynamic(DynamicConfig(n_seeds=1, moving=(0,), planners=("fusion",)), workers=0)


def test_paired_comparison_from_the_episode_csv(files):
    eps = read_csv(files["episodes_csv"])
    paired = read_csv(files["paired_csv"])
    others = [p for p in CFG.planners if p != "fusion"]
    assert [(int(r["moving"]), r["other"]) for r in paired] == \
        [(k, o) for k in CFG.moving for o in others]
    ok = {(e["moving"], e["index"], e["planner"]): e["status"] == "SUCCESS" for e in eps}
    for r in paired:
        pairs = [(ok[(r["moving"], str(i), "fusion")], ok[(r["moving"], str(i), r["other"])])
                 for i in range(CFG.n_seeds)]
        assert int(r["both"]) == sum(a and b for a, b in pairs)
        assert int(r["only_reference"]) == sum(a and not b for a, b in pairs)
        assert int(r["only_other"]) == sum(b and not a for a, b in pairs)
        assert int(r["neither"]) == sum(not a and not b for a, b in pairs)
        d = int(r["only_reference"]) + int(r["only_other"])
        # exact two-sided McNemar: sum of binomial(d, 1/2) probabilities <= that observed
        probs = [math.comb(d, j) / 2 ** d for j in range(d + 1)]
        obs = probs[int(r["only_reference"])] if d else 1.0
        p = sum(q for q in probs if q <= obs * (1 + 1e-7)) if d else 1.0
        assert float(r["p_value"]) == pytest.approx(min(1.0, p), rel=1e-9)
    # with 3 discs astar (following its path blindly) lost scenarios the fusion reached
    row = next(r for r in paired if r["moving"] == "3" and r["other"] == "astar")
    assert int(row["only_reference"]) > int(row["only_other"])


def test_success_plot_accepts_rates_at_0_and_1(tmp_path):
    from pathfuse.stats import wilson_ci
    from pathfuse.viz.animate import plot_success_vs_moving

    rows = []
    for k, n in ((0, 50), (50, 50), (0, 7), (7, 7), (3, 7)):
        p, lo, hi = wilson_ci(k, n)
        assert (k > 0 or lo == 0.0) and (k < n or hi == 1.0)
        rows.append({"planner": f"p{k}-{n}", "moving": 2, "reached_rate": p,
                     "reached_ci_low": lo, "reached_ci_high": hi})
    # an interval end that rounding put a hair beyond the rate must not break the plot
    rows.append({"planner": "eps", "moving": 2, "reached_rate": 0.0,
                 "reached_ci_low": 1e-17, "reached_ci_high": 0.07})
    out = tmp_path / "s.png"
    plot_success_vs_moving(rows, out)
    assert Image.open(out).format == "PNG"
