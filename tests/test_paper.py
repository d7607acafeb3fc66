"""The paper reproduction: every run kept, statistics right, files written."""

import csv
import math

import numpy as np
import pytest
from scipy import stats

from pathfuse.result import ConfigError
from pathfuse.studies.paper import (
    PAPER_PLANNERS,
    PaperConfig,
    mean_ci,
    run_paper,
    summary_rows,
    wilson_ci,
    write_paper_outputs,
)


def test_mean_ci_matches_scipy_t_interval():
    x = np.random.default_rng(1).normal(3.0, 2.0, size=37)
    m, lo, hi = mean_ci(x)
    ref = stats.t.interval(0.95, len(x) - 1, loc=x.mean(), scale=stats.sem(x))
    assert m == pytest.approx(x.mean())
    assert (lo, hi) == pytest.approx(ref)
    assert all(math.isnan(v) for v in mean_ci([]))


def test_wilson_interval_known_values():
    # Wilson score interval for 8/10 at 95%: [0.4902, 0.9433] (textbook value)
    p, lo, hi = wilson_ci(8, 10)
    assert p == 0.8
    assert lo == pytest.approx(0.4902, abs=1e-4) and hi == pytest.approx(0.9433, abs=1e-4)
    assert wilson_ci(0, 5)[1] == 0.0 and wilson_ci(5, 5)[2] == 1.0


def test_config_validation():
    with pytest.raises(ConfigError, match="n_seeds"):
        PaperConfig(n_seeds=0)
    with pytest.raises(ConfigError, match="fusion"):
        PaperConfig(planners=("astar", "apf"))


@pytest.fixture(scope="module")
def small_run():
    return run_paper(PaperConfig(n_seeds=6, first_seed=10, figure_seed=12))


def test_every_run_is_kept(small_run):
    recs = small_run.records
    columns = [c for c, _, _ in small_run.config.columns()]
    assert set(PAPER_PLANNERS) <= set(columns)
    assert len(recs) == 6 * len(columns)
    assert {(r["seed"], r["planner"]) for r in recs} == {
        (s, p) for s in range(10, 16) for p in columns
    }
    for r in recs:
        assert r["status"] == "SUCCESS" or not r["success"]
        assert r["time_s"] >= 0


def test_summary_counts_failures_and_pairs(small_run):
    rows = {r["planner"]: r for r in summary_rows(small_run, "pathfuse")}
    for name, row in rows.items():
        recs = small_run.by_planner(name)
        assert row["maps"] == 6
        assert row["successes"] == sum(r["success"] for r in recs)
        ok = [r["length_m"] for r in recs if r["success"]]
        if ok:
            assert row["length_mean_m"] == pytest.approx(np.mean(ok))
    fus = {r["seed"]: r for r in small_run.by_planner("fusion")}
    ast = {r["seed"]: r for r in small_run.by_planner("astar")}
    both = [s for s in fus if fus[s]["success"] and ast[s]["success"]]
    expect = np.mean([(fus[s]["length_m"] - ast[s]["length_m"]) / ast[s]["length_m"] for s in both])
    assert rows["astar"]["r_length_pairs"] == len(both)
    assert rows["astar"]["r_length_mean"] == pytest.approx(expect)


def test_outputs_are_written(small_run, tmp_path):
    files = write_paper_outputs(small_run, tmp_path / "out")
    for f in files.values():
        assert f.exists() and f.stat().st_size > 0
    md = files["tables_md"].read_text()
    assert "Table I" in md and "Table II" in md and "seed 12" in md
    for label in ("A-star", "Reference method [6]", "Fusion algorithm"):
        assert label in md
    with open(files["runs_csv"]) as fh:
        assert len(list(csv.DictReader(fh))) == len(small_run.records)
    assert files["fig3_png"].read_bytes()[:4] == b"\x89PNG"
