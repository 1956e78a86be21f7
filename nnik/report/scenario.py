"""Section: the scenario (machine, actuator, network, data)."""

from __future__ import annotations

from pathlib import Path

from nnik.report.document import Cell, Section, Table, lookup, num, txt


def build(ctx) -> Section:
    m, scn = ctx.m, ctx.inp.scenario
    sec = Section("scenario", "Scenario")
    t = Table("scenario-table", "Machine, actuator and network", ["item", "value"])
    add = lambda k, v: t.rows.append([txt(k, "key"), v if isinstance(v, Cell) else txt(v)])  # noqa: E731
    add("name", m.get("name"))
    if scn is not None and scn.raw.get("description"):
        add("description", scn.raw.get("description"))
    add("scenario file", m.get("scenario"))
    add("mechanism", m.get("mechanism"))
    if scn is not None:
        mech = scn.mechanism
        params = {k: v for k, v in mech.params.items() if v is not None and k not in ("distortion", "csv")}
        add("mechanism kind", f"{mech.kind} ({mech.family})")
        add("parameters", ", ".join(f"{k} = {v:g}" if isinstance(v, float) else f"{k} = {v}"
                                    for k, v in params.items()) or "—")
        dist = getattr(mech, "dist", None)
        if dist:
            add("distortion", ", ".join(f"{k} = {v:g}" for k, v in dist.items()))
        if mech.family == "measured":
            add("measurements", f"{Path(mech.params.get('csv', '?')).name} ({len(mech.positions_mm)} rows)")
        ws = scn.workspace
        add("workspace", f"x {ws.x_mm[0]:g} … {ws.x_mm[1]:g} mm, y {ws.y_mm[0]:g} … {ws.y_mm[1]:g} mm "
                         f"({ws.x_mm[1] - ws.x_mm[0]:g} × {ws.y_mm[1] - ws.y_mm[0]:g} mm)")
    else:
        add("parameters / workspace", Cell(f"not available — {ctx.inp.scenario_reason}", cls="notrun"))
    add("actuator", m.get("actuator"))
    if ctx.phys is not None:
        add("actuator resolution", ctx.phys.resolution)
    else:
        add("actuator resolution", Cell(f"not available — {ctx.phys_reason}", cls="notrun"))
    add("outputs", ", ".join(f"{o} ({ctx.unit})" for o in ctx.outputs))
    net = m.get("network") or {}
    add("network", f"{'-'.join(map(str, net.get('shape', [])))} tanh MLP, {net.get('mode', '?')} mode, "
                   f"inputs {'normalised to [-1, 1]' if net.get('normalize') else 'raw mm (not normalised)'}")
    add("weights (count)", num(net.get("parameters"), 0, "network/parameters"))
    wb = lookup(m, "fixed", "weights_bytes")
    if wb is not None:
        add("weights (bytes, fixed point)", num(wb, 0, "fixed/weights_bytes"))
    else:
        add("weights (bytes, fixed point)", Cell("not run — no `fixed` section in metrics.json", cls="notrun"))
    ds = m.get("dataset") or {}
    add("data", f"{ds.get('n_train', '?')} train, {ds.get('n_val', '?')} validation, "
                f"{ds.get('n_test', '?')} test points; truth: {ds.get('truth', '?')}")
    sec.tables.append(t)
    return sec
