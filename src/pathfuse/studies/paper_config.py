"""Settings of the paper reproduction (:mod:`pathfuse.studies.paper`): planners, variants,
references, and the paper's own values."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from pathfuse.result import ConfigError
from pathfuse.validate import short as _shown

__all__ = ["PAPER_PLANNERS", "PAPER_LABELS", "PAPER_TABLE", "PAPER_VARIANT", "REFERENCES",
           "VARIANTS", "PaperConfig", "PaperRun"]

#: Column order of the paper's tables (the fusion planner last, as in Table I).
PAPER_PLANNERS = ("astar", "apf", "ref6", "ref7", "fusion")
PAPER_LABELS = {
    "astar": "A-star",
    "apf": "Artificial potential field method",
    "ref6": "Reference method [6]",
    "ref7": "Reference method [7]",
    "fusion": "Fusion algorithm",
}
#: Table I/II values printed in the paper (one map, MATLAB on an i7-8750H).
PAPER_TABLE = {
    "length_m": {"astar": 14.7279, "apf": 15.0897, "ref6": 15.8056, "ref7": 15.8767,
                 "fusion": 14.2182},
    "time_s": {"astar": 2.1280, "apf": 0.7380, "ref6": 2.6650, "ref7": 2.3910, "fusion": 3.3180},
}
_APF_PLANNERS = {"apf", "fusion", "ref6", "ref7"}
#: The variants of the reproduction (see the module docstring).
VARIANTS = ("pathfuse", "paper")
_AS_PRINTED = {"safe_step": False, "stall_exit": False}
#: What the ``paper`` variant sets, per planner: the algorithms as printed.
PAPER_VARIANT: dict[str, dict[str, Any]] = {
    "apf": dict(_AS_PRINTED),
    "ref6": dict(_AS_PRINTED),
    "ref7": dict(_AS_PRINTED),
    "fusion": {**_AS_PRINTED, "ahead": "paper-x", "escape": False},
}
#: Any-angle references and the true shortest path, run in every variant's table.
REFERENCES = ("astar-smooth", "thetastar", "shortest")
PAPER_LABELS.update({
    "astar-smooth": "A-star + smoothing",
    "thetastar": "Theta*",
    "lazy-thetastar": "Lazy Theta*",
    "shortest": "Shortest path",
})


@dataclass(frozen=True)
class PaperConfig:
    """Settings of the reproduction.

    Attributes
    ----------
    n_seeds : int
        Number of maps (seeds ``first_seed .. first_seed + n_seeds - 1``).
    first_seed : int
        Seed of the first map.
    figure_seed : int
        The map drawn in Fig. 3 and reported in the one-map tables.
    planners : tuple of str
        Registry names; ``fusion`` must be among them for R_length / R_time.
    k_att, k_rep, rho0_m : float
        The paper's potential-field constants, given to every APF-based planner.
    step_m : float
        One step length (metres) for all four stepping planners (apf, ref6,
        ref7, fusion), so that their lengths and times compare like for like.
        The planners' own defaults differ (fusion steps 0.5 cells by default,
        the others 0.1); 0.1 m is the finer, more faithful choice.
    params : dict
        Extra per-planner parameters, ``{name: {key: value}}``.
    variants : tuple of str
        ``"pathfuse"`` and/or ``"paper"`` (see the module docstring); the first
        one is drawn in Fig. 3 and reported in the one-map tables.
    corner_cutting : bool
        The A* column cuts corners.
    references : tuple of str
        Global planners added to every table (``shortest`` gives the excess).
    """

    n_seeds: int = 100
    first_seed: int = 0
    figure_seed: int = 0
    planners: tuple[str, ...] = PAPER_PLANNERS
    k_att: float = 40.0
    k_rep: float = 5.0
    rho0_m: float = 2.0
    step_m: float = 0.1
    params: dict[str, dict[str, Any]] = field(default_factory=dict)
    variants: tuple[str, ...] = VARIANTS
    corner_cutting: bool = False
    references: tuple[str, ...] = REFERENCES

    def __post_init__(self) -> None:
        if not isinstance(self.n_seeds, int) or self.n_seeds < 1:
            raise ConfigError(f"n_seeds: must be a positive integer, got {_shown(self.n_seeds)}")
        if "fusion" not in self.planners:
            raise ConfigError("planners: must include 'fusion' (R_length is relative to it)")
        bad = [v for v in self.variants if v not in VARIANTS]
        if bad or not self.variants or len(set(self.variants)) != len(self.variants):
            raise ConfigError(f"variants: must be distinct values of {', '.join(VARIANTS)}, "
                              f"got {self.variants!r}")

    def column(self, name: str, variant: str) -> str:
        """The column (planner configuration) of ``name`` in the table of ``variant``:
        ``fusion`` or ``fusion/paper``."""
        if variant == "paper" and name in PAPER_VARIANT:
            return f"{name}/paper"
        return name

    def table_columns(self, variant: str) -> list[str]:
        """The columns of the table of ``variant``: the planners, then the references."""
        cols = [self.column(n, variant) for n in self.planners]
        return cols + [r for r in self.references if r not in cols]

    def columns(self) -> list[tuple[str, str, str]]:
        """Every configuration run, once: ``(column, registry name, variant)``."""
        seen: dict[str, tuple[str, str, str]] = {}
        for v in self.variants:
            for n in (*self.planners, *self.references):
                col = self.column(n, v)
                seen.setdefault(col, (col, n, v))
        return list(seen.values())

    def planner_params(self, name: str, variant: str = "pathfuse") -> dict[str, Any]:
        base: dict[str, Any] = {}
        if name in _APF_PLANNERS:
            base = {"k_att": self.k_att, "k_rep": self.k_rep, "rho0_m": self.rho0_m,
                    "step_m": self.step_m}
        if name == "astar" and self.corner_cutting:
            base["corner_cutting"] = True
        if variant == "paper":
            base.update(PAPER_VARIANT.get(name, {}))
        base.update(self.params.get(name, {}))
        return base

    def label(self, column: str) -> str:
        """The column's heading."""
        name, _, variant = column.partition("/")
        text = PAPER_LABELS.get(name, name)
        if name == "astar" and self.corner_cutting:
            text += " (corner cutting)"
        return f"{text} (as printed)" if variant == "paper" else text


@dataclass
class PaperRun:
    """All records of a reproduction: one dict per (seed, planner), seed-major."""

    config: PaperConfig
    records: list[dict[str, Any]]
    wall_s: float
    results: dict[tuple[int, str], Any] = field(default_factory=dict, repr=False)
    summary: Any = None
    """The :class:`~pathfuse.bench.runner.SweepSummary` of the engine run."""

    def by_planner(self, column: str) -> list[dict[str, Any]]:
        """The records of one column (``fusion``, ``fusion/paper``, ``shortest``...)."""
        return [r for r in self.records if r["planner"] == column]

    def seeds(self) -> list[int]:
        return sorted({r["seed"] for r in self.records})
