"""One table row per job for the CLI and the report (contour error, segment rate, chip check)."""

from __future__ import annotations

from nnik.dynamics.shaper_figures import describe

JOB_HEADER = ("scenario", "job", "segments", "steps", "contour max / RMS (µm)", "IK max (µm)", "rounding max (µm)",
              "chord max (µm)", "chip steps", "cycles/sample", "sample loop CPU", "flash / RAM (B)",
              "tool on / travel (mm)", "tool on-time (s)", "chip tool changes", "job time (s)",
              "peak step rate / limit (Hz)", "planner / shaper", "with belts: contour max / RMS (µm)",
              "ringing / floor (µm)", "compensation", "shapers (Klipper's vibration, smoothing, max accel)")


def _um(s: dict | None, rms: bool = False) -> str:
    if not s:
        return "-"
    return f"{s['max']:.1f} / {s['rms']:.1f}" if rms else f"{s['max']:.2f}" if s["max"] < 10 else f"{s['max']:.1f}"


def _cycles(c: dict, cps: dict) -> str:
    """Busy cycles a sample on average, the longest busy stretch inside the motion and of all, and
    the samples computed too late (the stepper's queue ran dry while the head moved)."""
    worst = f"worst sample {c['worst_sample_cycles']}, " if "worst_sample_cycles" in c else ""
    missed = f", {c['missed_samples']} missed" if "missed_samples" in c else ""
    return f"{cps['mean']:.0f} ({worst}longest stretch {cps['max']}{missed})"


def job_row(r: dict) -> tuple[str, ...]:
    c = r["chip"]
    t = r.get("tool") or {}
    tool = (f"{t['on_mm']:.1f} / {t['travel_mm']:.1f}", f"{t['on_s']:.2f}") if t else ("-", "-")
    if "not_run" in c:
        chip = (f"not run ({c['not_run']})", "-", "-", "-", "-")
    else:
        same = "equal" if c["steps_equal"] and c["replies_equal"] else "DIFFER"
        cps = c.get("cycles_per_sample")
        cpu = c.get("cpu_sample_loop")
        chip = (f"{c['steps']} {same}", _cycles(c, cps) if cps else "-",
                f"{100 * cpu:.1f} %" if cpu is not None else "-",
                f"{c['flash_bytes']} / {c['ram_bytes']}" + (f" + {c['stack_bytes']} stack" if c.get("stack_bytes") else ""),
                f"{c['tool_changes']} {'equal' if c['tool_equal'] else 'DIFFER'}" if "tool_equal" in c else "-")
    m = r.get("motion") or {}
    motion = (f"{m['job_s']:.3f}", f"{m['peak_step_rate_hz']:.0f} / {m['step_rate_limit_hz']}"
              + (f" ({m['overspeed_samples']} samples stretched)" if m["overspeed_samples"] else ""),
              f"{m['accel_mm_s2'][0]:g}/{m['accel_mm_s2'][1]:g} mm/s², {m['sample_hz']} Hz, {m['shaper']}"
              + (f" ({m['shaper_ram_bytes']} B)" if m["shaper_ram_bytes"] else "")) if m else ("-", "-", "-")
    d = r.get("dynamics")
    if d:
        tip = r["tip"]
        pick = d["pick"]
        how = d["chosen"] + (f" (auto: {pick['traded'] or 'nothing to trade'})" if "traded" in pick else "")
        belts = (_um(tip["contour_um"], True), f"{tip['ringing_um']['max']:.1f} / {tip['ringing_floor_um']['max']:.1f}", how)
    else:
        belts = ("- (no [dynamics])", "-", "-")
    return (r["scenario"], r["job"], str(r["segments"]), str(r["steps"]), _um(r["contour_um"], True), _um(r["ik_um"]),
            _um(r.get("rounding_um")), _um(r.get("chord_um")), *chip[:4], *tool, chip[4], *motion, *belts,
            "; ".join(f"{f['axis']}: {describe(f)}" for f in m.get("shaper_figures", ())) or "-")
