"""One table row per job for the CLI and the report (contour error, segment rate, chip check)."""

from __future__ import annotations

JOB_HEADER = ("scenario", "job", "segments", "steps", "contour max / RMS (µm)", "IK max (µm)", "rounding max (µm)",
              "chord max (µm)", "chip steps", "cycles/segment", "segments/s at 50 % CPU", "flash / RAM (B)",
              "tool on / travel (mm)", "tool on-time (s)", "chip tool changes")


def _um(s: dict | None, rms: bool = False) -> str:
    if not s:
        return "-"
    return f"{s['max']:.1f} / {s['rms']:.1f}" if rms else f"{s['max']:.2f}" if s["max"] < 10 else f"{s['max']:.1f}"


def job_row(r: dict) -> tuple[str, ...]:
    c = r["chip"]
    t = r.get("tool") or {}
    tool = (f"{t['on_mm']:.1f} / {t['travel_mm']:.1f}", f"{t['on_s']:.2f}") if t else ("-", "-")
    if "not_run" in c:
        chip = (f"not run ({c['not_run']})", "-", "-", "-", "-")
    else:
        same = "equal" if c["steps_equal"] and c["replies_equal"] else "DIFFER"
        cps = c.get("cycles_per_segment")
        rate = c.get("segment_rate_hz")
        chip = (f"{c['steps']} {same}", f"{cps['mean']:.0f} (longest stretch {cps['max']})" if cps else "-",
                f"{rate['mean']:.0f}" if rate else "-",
                f"{c['flash_bytes']} / {c['ram_bytes']}",
                f"{c['tool_changes']} {'equal' if c['tool_equal'] else 'DIFFER'}" if "tool_equal" in c else "-")
    return (r["scenario"], r["job"], str(r["segments"]), str(r["steps"]), _um(r["contour_um"], True), _um(r["ik_um"]),
            _um(r.get("rounding_um")), _um(r.get("chord_um")), *chip[:4], *tool, chip[4])
