"""Section (measured machines only): the reference model fitted to the marks, what its error
against the machine is estimated to be, and how the pick's claimed accuracy is made up."""

from __future__ import annotations

from nnik.report.document import D_UNIT, Section, Table, lookup, num, txt


def claim_sentence(ref: dict, row: dict, unit: str) -> str:
    """The pick's claimed max error: its error field against the reference combined with the
    reference's bootstrapped error fields (nnik.machine.ref_claim)."""
    return (f"The pick claims max {row['claimed_max']:.3g} {unit} against the machine inside the marks' hull "
            f"(pre-rounding; the C's rounding adds up to 0.5): the {ref.get('claim_level', 0.9):g} quantile, over the "
            f"reference's bootstrap replicates, of the max of its error against the reference "
            f"({row['pre_max']:.3g} {unit} at most) plus the replicate's error field (the reference alone: "
            f"{ref['error_max']:.3g} {unit}). "
            f"The noise floor of the readings is {ref['noise_floor']:.3g} {unit} (1 sigma).")


def build(ctx) -> Section | None:
    ref = ctx.m.get("reference")
    if not isinstance(ref, dict):
        return None
    unit = ctx.unit
    sec = Section("reference", "Measured machine: the reference model and honest accuracy")
    hull = ref.get("hull", {})
    sec.paragraphs.append(
        f"The machine is known only by {ref['marks']} marks. Every family compiles a reference model fitted to them "
        f"({ref['chosen']}{', ' + ref['detail'] if ref.get('detail') else ''}), chosen by {ref['folds']}-fold "
        f"cross-validation among the candidates below, on a dense grid inside the marks' convex hull "
        f"(x {hull.get('x_mm', ['?', '?'])[0]:.4g} … {hull.get('x_mm', ['?', '?'])[1]:.4g} mm, "
        f"y {hull.get('y_mm', ['?', '?'])[0]:.4g} … {hull.get('y_mm', ['?', '?'])[1]:.4g} mm). Noise: "
        f"{ref['noise']['source']}. Estimated error of the reference against the machine, net of that noise: "
        f"max {ref['error_max']:.3g} {unit}, RMS {max(ref['est_rms']):.3g} {unit} ({ref['method']}).")
    if ref.get("workspace_warning"):
        sec.paragraphs.append("Warning: " + ref["workspace_warning"] + ".")
    sel = ctx.m.get("selection") or {}
    pick = next((r for r in sel.get("implementations") or [] if r.get("picked") and "claimed_max" in r), None)
    if pick is not None:
        sec.paragraphs.append(claim_sentence(ref, pick, unit))
    src = lookup(sel, "target", "max_error_source")
    if src:
        sec.paragraphs.append(f"max_error {lookup(sel, 'target', 'max_error'):g} {unit} ({src}) applies to that claim.")
    t = Table("reference-candidates", "Reference candidates: held-out RMS residual per output (includes the noise)",
              ["candidate", f"CV RMS ({unit})", f"CV max ({unit})", "note", "chosen"])
    for name, c in (ref.get("candidates") or {}).items():
        if "skipped" in c:
            t.rows.append([txt(name, "label"), txt("—"), txt("—"), txt(c["skipped"]), txt("")])
            continue
        note = c.get("scored_on") or (f"smoothing {c['smoothing']:g}" if "smoothing" in c else "")
        t.rows.append([txt(name, "label"), txt(" / ".join(f"{v:.4f}" for v in c["cv_rms"])),
                       num(max(c["cv_max_abs"]), D_UNIT), txt(note), txt("chosen" if name == ref["chosen"] else "")])
    sec.tables.append(t)
    return sec
