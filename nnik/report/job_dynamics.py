"""The jobs section's belt dynamics (issue 18): per job with a [dynamics] table, the methods
compared (method -> the tip's contour max / RMS, ringing, residual vibration, job time, the
shaper's SRAM, and for the method the chip ran: flash, SRAM and the sample loop's CPU), the
same with the true machine off (f +-20 %, zeta halved), and the picture of the tip."""

from __future__ import annotations

from nnik.report.document import Table, txt

METHOD_HEADER = ["method", "contour max / RMS (µm)", "ringing (µm)", "floor (µm)", "residual vibration",
                 "job time (s)", "shaper SRAM (B)", "flash / RAM on the Uno (B)", "sample loop CPU"]


def _f(v, fmt="{:.1f}"):
    return "—" if v is None else fmt.format(v)


def method_rows(res: dict) -> list[list[str]]:
    """Plain rows (strings) of the methods table, the chosen method marked."""
    dyn = res["dynamics"]
    chosen = dyn["chosen"]
    chip = res.get("chip") or {}
    rows = []
    for m, r in dyn["methods"].items():
        if "error" in r:
            rows.append([m, f"n/a: {r['error']}", "", "", "", "", "", "", ""])
            continue
        here = m == chosen and "not_run" not in chip
        cpu = chip.get("cpu_sample_loop") if here else None
        rows.append([m + (" (chosen)" if m == chosen else ""),
                     f"{r['contour_um']['max']:.1f} / {r['contour_um']['rms']:.1f}",
                     _f(r["ringing_um"]["max"]), _f(r["ringing_floor_um"]["max"]),
                     _f(r.get("residual_pct"), "{:.0f} %"), f"{r['seconds']:.3f}",
                     str(r.get("shaper_ram_bytes", 0)),
                     f"{chip['flash_bytes']} / {chip['ram_bytes']}" if here else "—",
                     _f(None if cpu is None else 100 * cpu, "{:.1f} %")])
    return rows


def robust_rows(res: dict) -> list[list[str]]:
    rows = []
    for m, r in res["dynamics"]["methods"].items():
        rb = r.get("robust")
        if not rb:
            continue
        rows.append([m] + [f"{rb[k]['contour_um']['max']:.1f} / {rb[k]['ringing_um']['max']:.1f}" for k in rb])
    return rows


def tables(res: dict) -> list[Table]:
    dyn = res["dynamics"]
    name = res["job"]
    pick = dyn["pick"]
    note = (f"Belts: f = {dyn['model']['f_hz']} Hz, ζ = {dyn['model']['zeta']} per Cartesian axis. Ringing: the tip's "
            "peak distance to the path 20–200 ms after each stop or corner; floor: the steps' own distance there "
            "(IK, rounding, chord, the microstep); residual vibration: ringing above the floor over the "
            "uncompensated run's. ")
    if "traded" in pick:
        note += f"auto chose {pick['method']} (target {pick['target_um']:.1f} µm, {pick['target_from']}): {pick['traded']}."
    t = Table(f"dyn-{name}", f"{name}: vibration compensation (the firmware's Python model, bit for bit the chip's steps)",
              METHOD_HEADER, note=note)
    for row in method_rows(res):
        t.rows.append([txt(v, "label" if i == 0 else "num") for i, v in enumerate(row)])
    out = [t]
    rr = robust_rows(res)
    if rr:
        keys = list(next(r["robust"] for r in dyn["methods"].values() if r.get("robust")))
        t2 = Table(f"dyn-robust-{name}", f"{name}: the same shapers with the true machine off (contour max / ringing, µm)",
                   ["method"] + keys, note="The shaper stays designed for the scenario's f and ζ; the tip follows "
                                          "the changed machine.")
        for row in rr:
            t2.rows.append([txt(v, "label" if i == 0 else "num") for i, v in enumerate(row)])
        out.append(t2)
    return out


def print_methods(console, res: dict) -> None:
    """`nnik job`'s console: the methods table, auto's trade, the precompensated job, the PNG."""
    from rich.table import Table as RichTable

    d = res["dynamics"]
    t = RichTable(title=f"the belts (f = {d['model']['f_hz']} Hz, zeta = {d['model']['zeta']}): every compensation "
                        "on the tip, from the firmware's steps")
    for h in METHOD_HEADER:
        t.add_column(h)
    for row in method_rows(res):
        t.add_row(*row)
    console.print(t)
    pick = d["pick"]
    if "traded" in pick:
        console.print(f"auto: {pick['method']} (contour target {pick['target_um']:.1f} µm, {pick['target_from']}); "
                      f"{pick['traded'] or 'nothing to trade'}")
    if "gcode" in pick:
        console.print(f"precompensated job: {pick['gcode']}")
    console.print(f"belts plot: {d['png']}")
