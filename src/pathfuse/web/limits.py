"""What one request of ``pathfuse serve`` may ask for, and the error that refuses it."""

from __future__ import annotations

from dataclasses import dataclass

from pathfuse.result import PathfuseError

__all__ = ["ApiError", "Limits"]


class ApiError(PathfuseError):
    """A request the server refuses, with its HTTP status."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


@dataclass(frozen=True)
class Limits:
    """What one request may ask for (``pathfuse serve`` options set them).

    Attributes
    ----------
    max_cells : int
        Cells of any map (uploaded, generated, blank or sent back edited).
    max_upload_bytes : int
        Size of an upload request (every file together).
    max_body_bytes : int
        Size of a JSON request body.
    time_budget_s : float
        Wall time of one request's computation; planners get it as their
        ``Budget.time_limit_s``.
    max_ticks : int
        Ticks of one simulated episode.
    max_discs : int
        Moving discs of one scenario.
    grace_s : float
        How long past ``time_budget_s`` the server waits for a computation
        before it stops its worker process and answers 503 (a planner stops
        at its budget, but the metrics and layers around it take a little
        longer).  A request waiting in the queue spends the same clock:
        every request is answered within ``time_budget_s + grace_s`` of its
        arrival.
    max_json_depth : int
        Nesting of a JSON body (objects and lists); deeper is a 400.
    """

    max_cells: int = 2048 * 2048
    max_upload_bytes: int = 32 * 1024 * 1024
    max_body_bytes: int = 16 * 1024 * 1024
    time_budget_s: float = 8.0
    max_ticks: int = 20000
    max_discs: int = 64
    grace_s: float = 1.0
    max_json_depth: int = 32


def _cells_ok(w: int, h: int, limits: Limits, what: str) -> None:
    if w * h > limits.max_cells:
        raise ApiError(413, f"{what}: {w} x {h} = {w * h} cells is more than this server's "
                            f"limit of {limits.max_cells} cells")
