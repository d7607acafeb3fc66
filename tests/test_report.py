"""Study reports: every number checked against an independent computation from SQL.

The study is a real sweep (pathfuse.bench.run_bench, workers=1) over three map entries:
paper maps, a random map with two queries per seed, and a dynamic head-on scenario.
Planners: A* (the experiment's reference), fusion with a two-value r1_m sweep (static and
online) and a plug-in "straight" planner that draws the straight segment (collides on
some maps), fails on seed 1 and raises on seed 3, so errors, failures and collisions all
occur.  The expected values are computed here from the database with sqlite3, numpy and
scipy directly, not with pathfuse.stats.
"""

from __future__ import annotations

import base64
import csv
import json
import math
import sqlite3
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from pathfuse.bench import run_bench
from pathfuse.bench.report import (
    build_report,
    load_study,
    r_length_values,
    swept_parameters,
    write_report,
)
from pathfuse.result import ConfigError

ROOT = Path(__file__).resolve().parents[1]
HEAD_ON = ROOT / "examples" / "scenarios" / "head_on.yaml"

PLUGIN = '''
from dataclasses import dataclass
import time
import numpy as np
from pathfuse.planners.registry import register_function
from pathfuse.result import PlanResult, Status


@dataclass(frozen=True)
class Params:
    seed: int = 0
    fail_seed: int = -1
    raise_seed: int = -1


def plan(grid, start, goal, params, budget):
    t0 = time.perf_counter()
    if params.seed == params.raise_seed:
        raise RuntimeError(f"straight: boom on seed {params.seed}")
    if params.seed == params.fail_seed:
        return PlanResult(Status.NO_PATH, time_s=time.perf_counter() - t0, message="no")
    path = np.array([start, goal], dtype=float)
    return PlanResult(Status.SUCCESS, path=path, length=float(np.hypot(*(goal - start))),
                      time_s=time.perf_counter() - t0, planner="straight")


register_function("straight", plan, Params, "straight segment (test plug-in)")
'''

EXPERIMENT = f"""
name: rstudy
imports: [straight_plugin.py]
reference: astar
seeds: 5
maps:
  - name: paper
    map: paper
  - name: random
    map: {{random: {{size: [20, 20], density: 0.15}}}}
    queries: {{random: 2, min_distance_m: 8}}
    seeds: [0, 1, 2]
  - name: head-on
    dynamic: {HEAD_ON}
    seeds: [0, 1]
planners:
  - astar
  - name: straight
    params: {{fail_seed: 1, raise_seed: 3}}
  - name: fusion
    params: {{r1_m: [1.0, 2.0]}}
"""

Z95 = 1.959963984540054


def wilson(k: int, n: int) -> tuple[float, float, float]:
    p = k / n
    den = 1 + Z95**2 / n
    c = (p + Z95**2 / (2 * n)) / den
    h = Z95 * math.sqrt(p * (1 - p) / n + Z95**2 / (4 * n * n)) / den
    return p, (0.0 if k == 0 else c - h), (1.0 if k == n else c + h)


def t_ci(x) -> tuple[float, float, float]:
    x = np.asarray(x, dtype=float)
    m = float(x.mean())
    if x.size == 1 or np.all(x == x[0]):
        return m, m, m
    lo, hi = stats.t.interval(0.95, x.size - 1, loc=m, scale=stats.sem(x))
    return m, float(lo), float(hi)


def boot_ci(x) -> tuple[float, float, float]:
    """The percentile bootstrap of the mean the report promises: 2000 resamples, seed 0."""
    x = np.asarray(x, dtype=float)
    m = float(x.mean())
    if x.size == 1:
        return m, m, m
    idx = np.random.default_rng(0).integers(0, x.size, size=(2000, x.size))
    lo, hi = np.quantile(x[idx].mean(axis=1), [0.025, 0.975])
    return m, float(lo), float(hi)


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    d = tmp_path_factory.mktemp("study")
    (d / "straight_plugin.py").write_text(PLUGIN)
    (d / "exp.yaml").write_text(EXPERIMENT)
    s = run_bench(d / "exp.yaml", d / "study.db", workers=1, progress=False)
    assert s.errors == 1 and s.ran == 50  # straight raised on paper seed 3
    out = d / "out"
    files = write_report(d / "study.db", out)
    return d / "study.db", out, files


def sql(db: Path, query: str, params=()) -> list[tuple]:
    con = sqlite3.connect(db)
    try:
        return con.execute(query, params).fetchall()
    finally:
        con.close()


def read_csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def num(text: str) -> float:
    return math.nan if text == "" else float(text)


def groups(db: Path) -> list[tuple]:
    """(entry, config, kind) of every (map entry, planner config) with runs."""
    return sql(db, "SELECT DISTINCT e.entry, c.name, r.kind FROM pathfuse_results r "
                   "JOIN pathfuse_experiments e ON e.experimentid = r.experimentid "
                   "JOIN plannerConfigs c ON c.id = r.plannerid")


def runs_of(db: Path, entry: str | None, config: str, kind: str) -> list[sqlite3.Row]:
    con = sqlite3.connect(db)
    con.row_factory = sqlite3.Row
    where = "c.name = ? AND r.kind = ?"
    args: list = [config, kind]
    if entry is not None:
        where += " AND e.entry = ?"
        args.append(entry)
    rows = con.execute("SELECT r.* FROM pathfuse_results r "
                       "JOIN pathfuse_experiments e ON e.experimentid = r.experimentid "
                       f"JOIN plannerConfigs c ON c.id = r.plannerid WHERE {where}",
                       args).fetchall()
    con.close()
    return rows


def check_row(row: dict[str, str], runs: list[sqlite3.Row], r_by_id: dict[int, float]):
    n = len(runs)
    solved = [r for r in runs if r["solved"]]
    errors = [r for r in runs if r["status_name"] == "ERROR"]
    assert int(row["runs"]) == n
    assert int(row["solved"]) == len(solved)
    assert int(row["errors"]) == len(errors)
    assert int(row["not_solved"]) == n - len(solved) - len(errors)
    p, lo, hi = wilson(len(solved), n)
    assert num(row["success_rate"]) == pytest.approx(p, abs=1e-12)
    assert num(row["success_ci_low"]) == pytest.approx(lo, abs=1e-9)
    assert num(row["success_ci_high"]) == pytest.approx(hi, abs=1e-9)
    cf = [r for r in solved if r["collision_free"] is not None]
    assert int(row["collision_checked"]) == len(cf)
    assert int(row["collision_free"]) == sum(r["collision_free"] for r in cf)
    assert int(row["collision_runs"]) == sum((r["collisions"] or 0) > 0 for r in runs)
    for key, col, sel in (("length", "solution_length", solved),
                          ("time", "time", [r for r in runs if r["status_name"] != "ERROR"]),
                          ("time_to_goal", "time_to_goal", solved)):
        vals = [r[col] for r in sel if r[col] is not None]
        unit = "_m" if key == "length" else "_s"
        assert int(row[f"{key}_n"]) == len(vals)
        if not vals:
            assert row[f"{key}_mean{unit}"] == ""
            continue
        m, lo, hi = t_ci(vals) if key == "length" else boot_ci(vals)
        if key != "length":  # a time: its interval stays within the data, above zero
            assert min(vals) <= num(row[f"{key}_ci_low{unit}"]) <= m
            assert m <= num(row[f"{key}_ci_high{unit}"]) <= max(vals)
        assert num(row[f"{key}_mean{unit}"]) == pytest.approx(m, rel=1e-12)
        assert num(row[f"{key}_ci_low{unit}"]) == pytest.approx(lo, rel=1e-9, abs=1e-12)
        assert num(row[f"{key}_ci_high{unit}"]) == pytest.approx(hi, rel=1e-9, abs=1e-12)
        assert num(row[f"{key}_median{unit}"]) == pytest.approx(float(np.median(vals)))
    rv = [r_by_id[r["id"]] for r in runs if r["id"] in r_by_id]
    assert int(row["r_length_pairs"]) == len(rv)
    assert int(row["r_length_shorter"]) == sum(v < 0 for v in rv)
    if rv:
        m, lo, hi = t_ci(rv)
        assert num(row["r_length_mean"]) == pytest.approx(m, rel=1e-12, abs=1e-15)
        assert num(row["r_length_median"]) == pytest.approx(float(np.median(rv)), abs=1e-15)
    else:
        assert row["r_length_mean"] == ""


def sql_pairs(db: Path, ref_config: str) -> dict[int, float]:
    """R_length of every run paired with ``ref_config`` on problem_key + seed, both solved."""
    rows = sql(db, """
        SELECT r.id, (r.solution_length - f.solution_length) / f.solution_length
        FROM pathfuse_results r
        JOIN pathfuse_results f ON f.problem_key = r.problem_key AND f.seed = r.seed
                               AND f.kind = r.kind
        JOIN plannerConfigs fc ON fc.id = f.plannerid
        WHERE fc.name = ? AND r.solved = 1 AND f.solved = 1""", (ref_config,))
    return dict(rows)


# --------------------------------------------------------------------------- numbers
def test_summary_matches_sql_per_entry_and_pooled(study):
    db, out, _ = study
    rows = read_csv(out / "summary.csv")
    stored = dict(sql(db, "SELECT id, R_length FROM pathfuse_results WHERE solved = 1 "
                          "AND R_length IS NOT NULL"))
    seen = set()
    for entry, config, kind in groups(db):
        [row] = [r for r in rows if r["scope"] == entry and r["config"] == config
                 and r["pooled"] == "False"]
        check_row(row, runs_of(db, entry, config, kind), stored)
        seen.add((entry, config))
    # pooled: one row per (kind, config) over every entry of the kind
    for kind, config in sql(db, "SELECT DISTINCT r.kind, c.name FROM pathfuse_results r "
                                "JOIN plannerConfigs c ON c.id = r.plannerid"):
        [row] = [r for r in rows if r["pooled"] == "True" and r["kind"] == kind
                 and r["config"] == config]
        assert row["scope"] == f"all {kind}"
        check_row(row, runs_of(db, None, config, kind), stored)
    assert len(rows) == len(seen) + len(sql(db, "SELECT DISTINCT kind, plannerid "
                                                "FROM pathfuse_results"))
    # every run is counted exactly once per scope kind
    entry_total = sum(int(r["runs"]) for r in rows if r["pooled"] == "False")
    assert entry_total == sql(db, "SELECT COUNT(*) FROM runs")[0][0] == 50


def test_errors_and_failures_are_counted_not_dropped(study):
    db, out, _ = study
    rows = read_csv(out / "summary.csv")
    [row] = [r for r in rows if r["scope"] == "paper" and r["config"] == "straight"]
    # seeds 0..4: seed 1 NO_PATH, seed 3 raised
    assert (row["runs"], row["solved"], row["not_solved"], row["errors"]) == ("5", "3", "1", "1")
    assert row["failures"] == "ERROR:1; NO_PATH:1"
    assert num(row["success_rate"]) == pytest.approx(3 / 5)
    # the straight segment crosses obstacles on some maps: the report must say so
    cf = sql(db, "SELECT SUM(collision_free), COUNT(*) FROM pathfuse_results "
                 "WHERE planner='straight' AND solved = 1")[0]
    assert cf[0] < cf[1]
    pooled = [r for r in rows if r["pooled"] == "True" and r["config"] == "straight"][0]
    assert int(pooled["collision_free"]) == cf[0]
    assert int(pooled["collision_checked"]) == cf[1]


def test_default_r_length_is_the_stored_reference_and_equals_sql_pairing(study):
    db, _, _ = study
    s = load_study(db)
    default = r_length_values(s)
    vs_astar = r_length_values(s, "astar")
    pairs = sql_pairs(db, "astar")
    # the stored R_length (experiment reference: A*) is the same pairing done in SQL
    assert set(default) == set(pairs) == set(vs_astar)
    for k, v in pairs.items():
        assert default[k] == pytest.approx(v, rel=1e-12, abs=1e-15)
        assert vs_astar[k] == pytest.approx(v, rel=1e-12, abs=1e-15)
    # no dynamic run has a length reference by default
    dyn = {r[0] for r in sql(db, "SELECT id FROM pathfuse_results WHERE kind = 'dynamic'")}
    assert not dyn & set(default)


def test_reference_config_pairs_on_problem_and_seed(study, tmp_path):
    db, _, _ = study
    ref = "fusion(r1_m=1)"
    rep = build_report(db, reference=ref)
    pairs = sql_pairs(db, ref)
    assert set(rep.r_length) == set(pairs)
    # static and dynamic runs pair within their kind (fusion ran in both)
    kinds = dict(sql(db, "SELECT id, kind FROM pathfuse_results"))
    assert {kinds[i] for i in pairs} == {"static", "dynamic"}
    files = rep.write(tmp_path / "o")
    rows = read_csv(files["summary_csv"])
    for entry, config, kind in groups(db):
        [row] = [r for r in rows if r["scope"] == entry and r["config"] == config]
        check_row(row, runs_of(db, entry, config, kind), pairs)
    # against itself: every solved run pairs with R = 0
    [own] = [r for r in rows if r["scope"] == "paper" and r["config"] == ref]
    assert num(own["r_length_mean"]) == 0.0 and own["r_length_pairs"] == own["solved"]
    assert ref in files["report_md"].read_text()


def test_bad_reference_and_param_are_one_line_errors(study):
    db, _, _ = study
    with pytest.raises(ConfigError, match=r"--reference fusion: planner fusion has 2 "
                                          r"configurations .*fusion\(r1_m=1\)"):
        build_report(db, reference="fusion")
    with pytest.raises(ConfigError, match=r"--reference nope: no such planner or "
                                          r"configuration .*astar"):
        build_report(db, reference="nope")
    with pytest.raises(ConfigError, match=r"--param r9: no planner .*r1_m"):
        build_report(db, params=["r9"])


# --------------------------------------------------------------------------- parameters
def test_swept_parameter_is_detected_per_kind(study):
    db, _, _ = study
    s = load_study(db)
    # straight's seed differs per run but not per configuration: not a sweep
    assert swept_parameters(s) == {("static", "fusion"): ["r1_m"],
                                   ("dynamic", "fusion"): ["r1_m"]}
    chosen = swept_parameters(s, ["k_att", "r1_m"])
    assert chosen[("static", "fusion")] == ["k_att", "r1_m"]
    assert ("static", "astar") not in chosen


def test_parameter_rows_pool_configs_by_value(study):
    db, out, files = study
    rows = read_csv(out / "parameters.csv")
    assert {(r["kind"], r["planner"], r["parameter"]) for r in rows} == {
        ("static", "fusion", "r1_m"), ("dynamic", "fusion", "r1_m")}
    stored = dict(sql(db, "SELECT id, R_length FROM pathfuse_results WHERE solved = 1 "
                          "AND R_length IS NOT NULL"))
    for r in rows:
        value = float(r["value"])
        where = ("r.planner = 'fusion' AND r.kind = ? "
                 "AND json_extract(c.settings, '$.r1_m') = ?")
        args: list = [r["kind"], value]
        if r["pooled"] == "False":
            where += " AND e.entry = ?"
            args.append(r["scope"])
        con = sqlite3.connect(db)
        con.row_factory = sqlite3.Row
        runs = con.execute("SELECT r.* FROM pathfuse_results r JOIN plannerConfigs c "
                           "ON c.id = r.plannerid JOIN pathfuse_experiments e "
                           f"ON e.experimentid = r.experimentid WHERE {where}",
                           args).fetchall()
        con.close()
        assert runs and int(r["configs"]) == 1
        check_row(r, runs, stored)
    for kind in ("static", "dynamic"):
        assert files[f"param_{kind}_fusion_r1_m"].is_file()


# --------------------------------------------------------------------------- files
def test_files_pngs_html_and_markdown(study):
    db, out, files = study
    pngs = sorted(p for p in files.values() if p.suffix == ".png")
    names = {p.name for p in pngs}
    for entry in ("paper", "random", "head-on"):
        assert f"length_{entry}.png" in names and f"time_{entry}.png" in names
    assert {"r_length_paper.png", "r_length_random.png", "time_to_goal_head-on.png",
            "r_length_all-static_pooled.png"} <= names
    assert "r_length_head-on.png" not in names  # no reference for dynamic runs
    for p in pngs:
        data = p.read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 2000
        from PIL import Image

        with Image.open(p) as im:
            im.verify()
    page = (out / "report.html").read_text()
    md = (out / "report.md").read_text()
    assert page.startswith("<!DOCTYPE html>") and "<style>" in page
    assert "<link" not in page and "<script" not in page  # self-contained
    for name in names:
        assert f"href='{name}'" in page
        assert f"({name})" in md
    embedded = page.count("src='data:image/png;base64,")
    assert embedded == len(pngs)
    first = page.split("src='data:image/png;base64,", 1)[1].split("'", 1)[0]
    assert base64.b64decode(first)[:4] == b"\x89PNG"
    # every table: the headers and every configuration name, with the CSV's counts
    for _entry, config, _ in groups(db):
        assert config in page and config in md
    rows = read_csv(out / "summary.csv")
    row = [r for r in rows if r["scope"] == "paper" and r["config"] == "straight"][0]
    cell = f"{row['solved']}/{row['runs']} = {100 * float(row['success_rate']):.1f}%"
    assert cell in md and cell in page
    for h in ("success [95% CI]", "R_length mean [95% CI]", "time to goal (s) mean [95% CI]",
              "collisions [95% CI]", "pairs"):
        assert h in md and h in page
    # 3 entries + the pooled static entries, each as three tables (outcomes, lengths and
    # times, R_length) narrow enough for a window: at most 9 columns
    assert md.count("\n| configuration |") == 12
    heads = [ln for ln in md.splitlines() if ln.startswith("| configuration |")
             or ln.startswith("| scope |")]
    assert heads and max(h.count(" | ") + 1 for h in heads) <= 9
    # no planning-time interval below zero; a row's mean, interval and median share decimals
    for ln in md.splitlines():
        cells = [c.strip() for c in ln.strip("|").split("|")]
        for c in cells:
            if " [" in c and c[0].isdigit() and "%" not in c:
                vals = c.replace("[", "").replace("]", "").replace(",", "").split()
                assert all(not v.startswith("-") for v in vals), ln
                assert len({len(v.split(".")[-1]) for v in vals}) == 1, c
    assert "### fusion (static): parameter r1_m" in md


def test_link_images_instead_of_embedding(study, tmp_path):
    db, _, _ = study
    files = write_report(db, tmp_path / "o", embed_images=False)
    page = files["report_html"].read_text()
    assert "base64" not in page
    for p in files.values():
        if p.suffix == ".png":
            assert f"src='{p.name}'" in page


# --------------------------------------------------------------------------- bad databases
def test_bad_databases_are_one_line_errors(tmp_path, study):
    with pytest.raises(ConfigError, match=r"nope\.db: no such study database"):
        load_study(tmp_path / "nope.db")
    (tmp_path / "text.db").write_text("not a database\n")
    with pytest.raises(ConfigError, match=r"text\.db: not an SQLite database"):
        load_study(tmp_path / "text.db")
    con = sqlite3.connect(tmp_path / "other.db")
    con.execute("CREATE TABLE runs (x)")
    con.commit()
    con.close()
    with pytest.raises(ConfigError, match=r"other\.db: not a pathfuse study database"):
        load_study(tmp_path / "other.db")
    with pytest.raises(ConfigError, match="is a folder"):
        load_study(tmp_path)
    from pathfuse.bench.store import ResultStore

    ResultStore(tmp_path / "empty.db").close()
    with pytest.raises(ConfigError, match=r"empty\.db: the study holds no runs yet"):
        load_study(tmp_path / "empty.db")
    # the report leaves the database as it was (opened read-only)
    db = study[0]
    before = db.read_bytes()
    build_report(db)
    assert db.read_bytes() == before


def test_config_names_and_parameter_columns(study):
    """Configs names repeated across kinds get no suffix; rows carry their parameters."""
    db, out, _ = study
    rows = read_csv(out / "summary.csv")
    fus = [r for r in rows if r["planner"] == "fusion"]
    assert {r["config"] for r in fus} == {"fusion(r1_m=1)", "fusion(r1_m=2)"}
    assert {r["param.r1_m"] for r in fus} == {"1", "2"}
    assert all(r["param.r1_m"] == "" for r in rows if r["planner"] != "fusion")
    # settings JSON is what the r1_m column reports
    for cfg, settings in sql(db, "SELECT name, settings FROM plannerConfigs c "
                                 "JOIN pathfuse_configs p ON p.plannerid = c.id "
                                 "WHERE p.planner = 'fusion'"):
        assert f"{json.loads(settings)['r1_m']:g}" in cfg


def test_excess_over_the_shortest_path_column(tmp_path):
    exp = tmp_path / "exp.yaml"
    exp.write_text("""
seeds: 4
maps:
  - {name: paper, map: paper}
planners: [astar, thetastar, shortest]
""")
    db = tmp_path / "s.db"
    run_bench(exp, db, workers=1)
    rep = build_report(db)
    con = sqlite3.connect(db)
    rows = con.execute(
        "SELECT c.name, r.seed, r.solution_length FROM pathfuse_results r JOIN plannerConfigs c "
        "ON r.plannerid = c.id WHERE r.solved = 1").fetchall()
    low = {seed: length for name, seed, length in rows if name == "shortest"}
    by = {r["config"]: r for r in rep.rows if r["scope"] == "paper"}
    for name in ("astar", "thetastar"):
        want = [(length - low[seed]) / low[seed] for n, seed, length in rows if n == name]
        assert by[name]["excess_pairs"] == 4
        assert by[name]["excess_mean"] == pytest.approx(np.mean(want))
        assert by[name]["excess_median"] == pytest.approx(np.median(want))
        assert min(want) > 0
    assert by["shortest"]["excess_pairs"] == 0
    files = write_report(db, tmp_path / "rep")
    md = Path(files["markdown"]).read_text() if "markdown" in files else \
        (tmp_path / "rep" / "report.md").read_text()
    assert "excess over the shortest path" in md
    # the command line prints it too
    import subprocess
    import sys

    p = subprocess.run([sys.executable, "-m", "pathfuse.cli", "report", str(db), "--out",
                        str(tmp_path / "rep2")], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert "excess over shortest" in p.stdout
    line = next(ln for ln in p.stdout.splitlines() if ln.startswith("all") and " astar " in ln)
    assert f"{100 * by['astar']['excess_mean']:+.2f}% (n=4)" in line

