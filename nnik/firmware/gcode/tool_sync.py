"""Where the tool switches on the shaped head path (issue 26 item 3).

A cut is a run of consecutive blocks whose tool is on (a laser's duty above 0, a pen down), from
its start S (the end of the block before it) to its end E.  On the head's path (the shaped points
the IK gets: Segments.ends_um) each switch is measured along that path:
  * lead: where the first tool-on segment starts, less where the path passes S (negative: the
    tool came on before the head reached the cut);
  * lag: where the last tool-on segment ends, less where the path passes E (positive: on after
    the head left the cut).
"Where the path passes" a point is its closest point to it while the shaped head can be there:
from the planner's first sample of the run (or its last) to the shaper's longest delay after.
Each switch comes with its step: the head's step on the segment it falls on (the first on, the
first off: a segment's tool is the one where it ends) plus the planner's
step across the cut's edge (a segment's tool is that of the planned sample its end maps to, and
the edge is known to lie in that sample, not where in it; without a shaper the two are the same
sample and the bound is one step).  The tool follows the head when |lead| and |lag| are within
that step (plus ROUND_UM of rounding).
"""

from __future__ import annotations

import numpy as np

ROUND_UM = 3.0  # whole-um shaped points (0.71 um each, two per switch) and the half-um arc increments


def cut_runs(tool: list[int], off_duty: int) -> list[tuple[int, int]]:
    """(first, last) push index of every run of consecutive blocks whose tool is on."""
    on = [(t & 0xFF) != off_duty for t in tool]
    runs, start = [], None
    for i, o in enumerate(on + [False]):
        if o and start is None:
            start = i
        elif not o and start is not None:
            runs.append((start, i - 1))
            start = None
    return runs


def _pass_at(path: np.ndarray, lo: int, hi: int, point) -> float:
    """Arc length along path (N, 2) where it passes closest to point, among its segments
    lo+1..hi (segment k runs from path[k-1] to path[k])."""
    a, b = path[lo:hi], path[lo + 1:hi + 1]
    d = b - a
    ll = (d * d).sum(1)
    t = np.clip(((np.asarray(point, float) - a) * d).sum(1) / np.where(ll > 0, ll, 1), 0, 1)
    dist = np.hypot(*(a + t[:, None] * d - point).T)
    k = int(np.argmin(dist))
    cum = np.concatenate([[0.0], np.cumsum(np.sqrt(ll))])
    return cum[k] + t[k] * np.sqrt(ll[k])


def switches(plan, seg, cfg) -> list[dict]:
    """Every cut's switch on and off on the shaped head path: lead_um, lag_um and the step_um of
    each (see the module's doc); runs whose samples the sampler passed over are left out."""
    path = np.vstack([[0.0, 0.0], np.asarray(seg.ends_um, float)])  # path[k]: after segment k - 1
    plan_pts = np.vstack([[0.0, 0.0], np.asarray(seg.planned_um, float)])
    plan_step = np.hypot(*np.diff(plan_pts, axis=0).T)  # plan_step[k]: the planner's motion in segment k
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
    on = np.asarray(seg.duty) != cfg.tool_off_duty
    blk, N, span = np.asarray(seg.block), len(seg.duty), cfg.shaper_len + 2
    out, after = [], 0  # after: the first sample past the previous cut's switch off
    for first, last in cut_runs(plan.tool, cfg.tool_off_duty):
        inside = np.flatnonzero((blk >= first) & (blk <= last))
        if not len(inside):
            continue
        n_s, n_e = int(inside[0]), int(inside[-1])
        n_from = max(n_s, after)
        ons = np.flatnonzero(on[n_from:min(N, n_s + span)])
        if not len(ons):
            out.append({"run": (first, last), "on_at": None})
            continue
        n_on = n_from + int(ons[0])
        offs = np.flatnonzero(~on[n_on:])
        n_last = n_on + (int(offs[0]) if len(offs) else N - n_on) - 1
        after = n_last + 1
        S = plan.ends[first - 1] if first else (0, 0)
        E = plan.ends[last]
        lo = max(n_s - 1, 0)
        s_pass = _pass_at(path, lo, min(N, n_s + span), S) + cum[lo]
        e_pass = _pass_at(path, n_e - 1 if n_e else 0, min(N, n_e + span), E) + cum[max(n_e - 1, 0)]
        out.append({"run": (first, last), "on_at": n_on, "off_after": n_last,
                    "lead_um": float(cum[n_on] - s_pass),
                    "on_step_um": float(cum[n_on + 1] - cum[n_on] + (plan_step[n_s] if cfg.shaper_len else 0)),
                    "lag_um": float(cum[n_last + 1] - e_pass),
                    "off_step_um": float(cum[min(n_last + 2, N)] - cum[n_last + 1]
                                         + (plan_step[min(n_e + 1, N - 1)] if cfg.shaper_len else 0))})
    return out


def summary(sw: list[dict]) -> dict:
    """The worst lead (mm, negative: early) and lag of a job's switches, and how many exceed a step."""
    got = [s for s in sw if s.get("on_at") is not None]
    if not got:
        return {"switches": 0}
    lead = np.array([s["lead_um"] for s in got])
    lag = np.array([s["lag_um"] for s in got])
    late = sum(abs(s["lead_um"]) > s["on_step_um"] + ROUND_UM or abs(s["lag_um"]) > s["off_step_um"] + ROUND_UM
               for s in got)
    return {"switches": len(got), "lead_mm": [float(lead.min()) / 1000, float(lead.max()) / 1000],
            "lag_mm": [float(lag.min()) / 1000, float(lag.max()) / 1000], "beyond_one_step": int(late)}
