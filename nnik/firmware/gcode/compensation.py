"""Vibration compensation for a job (issue 18): every method run through the firmware's Python
model (bit for bit the chip's steps), the tip integrated from its steps, and the pick.

Residual vibration is a method's ringing above the floor (the steps' own distance to the path in
the same windows: IK, rounding, chord and the microstep, which no shaper removes) over the
uncompensated ringing above its floor.

Methods: "none", the input shapers "zv", "mzv", "zvd", "ei" (on the chip, at the [dynamics]
resonance) and "precompensated" (nnik.dynamics.precompensate: the job rewritten offline, run
without a shaper).  Each gets the tip's contour max / RMS (um), its ringing (the peak deviation
20-200 ms after stops and corners), residual vibration (its ringing over the uncompensated one)
and the job's time.  Robustness repeats the tip with the true machine off: f +-20 %, zeta halved.

auto picks the method that meets the contour target at the least job time: [motion]
max_contour_um, or without one, within 25 % of the best method's contour max.
"""

from __future__ import annotations

from pathlib import Path
from dataclasses import replace

import numpy as np

from nnik.dynamics.precompensate import gcode as pc_gcode
from nnik.dynamics.precompensate import precompensated
from nnik.dynamics.shapers import KINDS
from nnik.files.atomic_write import write_file_atomic
from nnik.firmware.config import axis_shapers
from nnik.firmware.gcode.motion import interpret, plan_steps
from nnik.firmware.gcode.steps import model_events
from nnik.firmware.gcode.tip import tip_report
from nnik.progress import bar

METHODS = ("none",) + KINDS + ("precompensated",)
AUTO_SLACK = 1.25  # without a target: within 25 % of the best contour max
SMOOTH_S = 0.005  # the precompensation's reference smoothing (two moving averages of 5 ms)
PC_EVERY_S = 0.005  # a precompensated G1 line every 5 ms: 115,200 baud sends one in under 3 ms
ROBUST = {"f +20 %": (1.2, 1.0), "f -20 %": (0.8, 1.0), "zeta / 2": (1.0, 0.5)}


def with_shaper(cfg, kind: str, dyn: dict, table: dict | None = None):
    """cfg with the shaper kind designed for dyn, or the [shaper] table's per-axis shapers when
    kind is its label (ValueError: one line, e.g. overdamped)."""
    taps, designs = axis_shapers(kind, dyn, table, cfg.sample_hz)
    return replace(cfg, shaper=kind, shaper_taps=taps, shaper_design=designs)


def model_run(lines: list[str], cfg, ik):
    plan = interpret(lines, cfg)
    bad = [r for r in plan.replies if r != "ok"]
    if bad:
        raise ValueError(bad[0].removeprefix("error: "))
    seg = plan_steps(plan, cfg, ik)
    return plan, seg, model_events(seg)


def _timeline(seg) -> np.ndarray:
    """The planned point at every sample period of the job (rests held for their ticks)."""
    per = np.where(seg.kind == 0, 1, np.maximum(1, -(-seg.ticks // max(1, seg.ticks_per_sample))))
    return np.repeat(seg.planned_um, per, axis=0), np.repeat(np.arange(len(per)), per)


def _tool_lines(seg, cfg, owner: np.ndarray) -> list[str]:
    """A tool line wherever the duty changes along the timeline (laser: M3 S / M5; pen: Z)."""
    duty = seg.duty[owner]
    out = [""] * len(duty)
    prev = cfg.tool_off_duty
    for k, d in enumerate(duty.tolist()):
        if d == prev:
            continue
        if cfg.tool == "laser":
            out[k] = "M5" if d == 0 else f"M3 S{d * cfg.s_max / 255:.3f}"
        else:
            out[k] = f"G1 Z{(cfg.pen_z_um + (1000 if d == cfg.pen_duty(False) else -1000)) / 1000:.3f}"
        prev = d
    return out


def precompensate_lines(seg, cfg, dyn: dict, source: str) -> tuple[list[str], list[int]]:
    """(G-code, the source sample of each line) of the job rewritten so the modelled tip follows
    its planned motion."""
    planned, owner = _timeline(seg)
    fs = cfg.sample_hz
    ref, base = precompensated(planned / 1000.0, fs, dyn["f_hz"], dyn["zeta"], SMOOTH_S)
    lead = (len(ref) - len(planned)) - (len(base) - len(ref))  # smooth() leads with rest
    lead = (len(ref) - len(planned)) // 2 if lead < 0 else lead
    owner = np.concatenate([np.full(lead, owner[0]), owner, np.full(len(base) - lead - len(owner), owner[-1])])
    tool = _tool_lines(seg, cfg, owner) if (seg.duty != cfg.tool_off_duty).any() else None
    header = ["; precompensated by nnik (model inversion of the belt axes on a reference smoothed",
              f"; by two {SMOOTH_S * 1000:g} ms moving averages) for f = {list(dyn['f_hz'])} Hz,",
              f"; zeta = {list(dyn['zeta'])}, from {source}"[:90]]
    lines, src = pc_gcode(base, fs, max(1, int(round(PC_EVERY_S * fs))), np.zeros(2), header, tool)
    move_of_line = [int(seg.move[owner[k]]) if k >= 0 else -1 for k in src]
    return lines, move_of_line


def evaluate(scn, cfg, plan, seg, ev, dyn: dict, moves=None, keep_track: bool = False) -> dict:
    r = tip_report(scn, cfg, plan, seg, ev, dyn, moves=moves, keep_track=keep_track)
    r["seconds"] = float(seg.ticks.sum() / cfg.tick_hz)
    return r


def _perturbed(dyn: dict, fk: float, zk: float) -> dict:
    return {"f_hz": tuple(f * fk for f in dyn["f_hz"]), "zeta": tuple(z * zk for z in dyn["zeta"])}


def compare(scn, cfg, lines: list[str], ik, dyn: dict, source: str, methods=METHODS, robust: bool = True,
            keep: tuple[str, ...] = ()) -> dict:
    """Every method on the job: {method: figures} plus "auto" (the pick and what it traded).
    Methods that cannot be built (e.g. an overdamped axis has nothing to shape) carry "error"."""
    runs, out = {}, {}
    # a long job (a raster of 100,000 lines) spends minutes here: each method's run is said on a terminal
    for m in bar(methods, desc="compensations: the firmware's model", unit="method", leave=False, position=1):
        if m == "precompensated":
            continue
        try:
            c = with_shaper(cfg, m, dyn, getattr(scn, "shaper", None))
            runs[m] = (c,) + model_run(lines, c, ik)
        except ValueError as exc:
            out[m] = {"error": str(exc)}
    if "precompensated" in methods and "none" in runs:
        c, plan, seg, ev = runs["none"]
        pc, move_of_line = precompensate_lines(seg, c, dyn, source)
        try:
            p_plan, p_seg, p_ev = model_run(pc, c, ik)
            line_move = np.asarray(move_of_line)
            # each precompensated move is measured against the programmed move it came from
            pm = np.array([line_move[mv.line_no - 1] for mv in p_plan.moves], dtype=np.int64)
            p_seg.move = np.maximum(pm[p_seg.move], 0)
            runs["precompensated"] = (c, p_plan, p_seg, p_ev)
            out["precompensated"] = {"gcode": pc, "lines": len(pc)}  # no wall-clock figure in a job's JSON
        except ValueError as exc:
            out["precompensated"] = {"error": f"precompensated job: {exc}"}
    programmed = runs["none"][1].moves if "none" in runs else None
    for m, (c, plan, seg, ev) in bar(runs.items(), total=len(runs), desc="compensations: the tip", unit="method",
                                     leave=False, position=1):
        r = evaluate(scn, c, plan, seg, ev, dyn, moves=programmed, keep_track=m in keep)
        if robust:
            r["robust"] = {k: {key: v for key, v in evaluate(scn, c, plan, seg, ev, _perturbed(dyn, *fz),
                                                             moves=programmed).items() if key in ("contour_um", "ringing_um", "ringing_floor_um")}
                           for k, fz in ROBUST.items()}
        out.setdefault(m, {}).update(r)
        out[m]["shaper_ram_bytes"] = c.shaper_ram_bytes
        out[m]["run"] = (c, plan, seg, ev)
    # residual vibration: the ringing above the steps' own deviation in the same windows (the
    # floor: IK, rounding, chord and the microstep, which no shaper can remove), over the
    # uncompensated run's
    none = out.get("none", {})
    if "ringing_um" in none:
        excess0 = none["ringing_um"]["max"] - none["ringing_floor_um"]["max"]
        for m, r in out.items():
            if "ringing_um" in r and excess0 > 0:
                r["residual_pct"] = 100.0 * max(0.0, r["ringing_um"]["max"] - r["ringing_floor_um"]["max"]) / excess0
    return out


def auto_pick(results: dict, target_um: float | None) -> dict:
    """The method meeting the contour target at the least job time (ties: smaller contour)."""
    ok = {m: r for m, r in results.items() if "contour_um" in r}
    best = min(r["contour_um"]["max"] for r in ok.values())
    target = target_um if target_um is not None else AUTO_SLACK * best
    meets = {m: r for m, r in ok.items() if r["contour_um"]["max"] <= target}
    if not meets:
        m = min(ok, key=lambda k: ok[k]["contour_um"]["max"])
        return {"method": m, "target_um": target, "met": False,
                "why": f"no method meets {target:.1f} um; {m} comes closest ({ok[m]['contour_um']['max']:.1f} um)"}
    m = min(meets, key=lambda k: (meets[k]["seconds"], meets[k]["contour_um"]["max"]))
    none = ok.get("none")
    traded = ""
    if none and m != "none":
        dt = 100.0 * (ok[m]["seconds"] / none["seconds"] - 1.0)
        traded = (f"{dt:+.1f} % job time for contour max {none['contour_um']['max']:.1f} -> "
                  f"{ok[m]['contour_um']['max']:.1f} um and ringing {none['ringing_um']['max']:.1f} -> "
                  f"{ok[m]['ringing_um']['max']:.1f} um")
    tighter = [k for k in meets if meets[k]["contour_um"]["max"] < ok[m]["contour_um"]["max"]]
    if tighter:
        k = min(tighter, key=lambda k: meets[k]["contour_um"]["max"])
        traded += (f"; {k} would give {meets[k]['contour_um']['max']:.1f} um in "
                   f"{meets[k]['seconds']:.3f} s")
    src = "[motion] max_contour_um" if target_um is not None else f"{AUTO_SLACK:g} x the best method's"
    return {"method": m, "target_um": target, "target_from": src, "met": True, "traded": traded.lstrip("; ")}


def _row(r: dict) -> dict:
    """The figures of one method, without its runs and tracks."""
    return {k: v for k, v in r.items() if k not in ("run", "track", "gcode")}


def job_dynamics(scn, cfg, lines: list[str], ik, shaper: str | None, precompensate: bool, source: str,
                 out_dir: Path, stem: str) -> tuple:
    """`nnik job` with a [dynamics] table: every method compared, the one asked for (--shaper, or
    the scenario's [motion] shaper; auto: auto_pick; --precompensate: the rewritten job) chosen.
    Returns (cfg, lines, figures, png): the machine and G-code the chip should run, the methods
    table with the pick and what it traded, and the picture.  ValueError: one line."""
    from nnik.firmware.gcode.plot_dynamics import dynamics_png

    dyn = scn.dynamics
    asked = "precompensated" if precompensate else (shaper or (scn.motion or {}).get("shaper", "none"))
    keep = ("none", asked) if asked != "auto" else tuple(METHODS)
    methods = METHODS + ((asked,) if asked not in METHODS + ("auto",) else ())  # + the [shaper] table's
    res = compare(scn, cfg, lines, ik, dyn, source, methods=methods, keep=keep)
    if asked == "auto":
        pick = auto_pick(res, (scn.motion or {}).get("max_contour_um"))
        chosen = pick["method"]
    else:
        if "error" in res.get(asked, {}):
            raise ValueError(f"{asked}: {res[asked]['error']}")
        chosen, pick = asked, {"method": asked, "asked": True}
    run_cfg = res[chosen]["run"][0]
    run_lines = res[chosen].get("gcode") or lines
    if chosen == "precompensated":
        pc_path = out_dir / f"{stem}_precompensated.gcode"
        write_file_atomic(pc_path, "\n".join(res[chosen]["gcode"]) + "\n")
        pick["gcode"] = str(pc_path)
    tracks = {m: res[m]["track"] for m in ("none", chosen) if "track" in res.get(m, {})}
    plan = res["none"]["run"][1]
    title = (f"{scn.name}: {stem}, belts f = {list(dyn['f_hz'])} Hz, zeta = {list(dyn['zeta'])}; "
             f"{chosen}: contour max {res[chosen]['contour_um']['max']:.1f} µm, "
             f"ringing {res[chosen]['ringing_um']['max']:.1f} µm")
    png = dynamics_png(out_dir / f"{stem}_dynamics.png", title, plan, cfg, tracks, chosen, res)
    figures = {"model": {"f_hz": list(dyn["f_hz"]), "zeta": list(dyn["zeta"]), "per": "Cartesian axis"},
               "chosen": chosen, "pick": pick, "methods": {m: _row(r) for m, r in res.items()}, "png": str(png)}
    return run_cfg, run_lines, figures, png
