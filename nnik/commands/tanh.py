"""`nnik tanh`: the MLP's integer tanh replacements and their errors over every input."""

from __future__ import annotations

from rich.table import Table

from nnik.commands import common_options as co
from nnik.report.console import console

HELP = "table of the MLP's integer tanh replacements and their errors, every int16 input swept"


def register(sub) -> None:
    p = co.add_command(sub, "tanh", HELP)
    p.set_defaults(func=cmd_tanh)


def cmd_tanh(args) -> None:
    from nnik.implementations.mlp import tanh as activations

    rows = activations.variants_table()
    t = Table(title="tanh replacements: int16 Q3.12 in, Q15 out, all 65536 inputs swept (errors in LSB of Q15)")
    for c in ("variant", "form", "segments", "degree", "float max", "float RMS", "int max LSB", "int RMS LSB",
              "mults", "bytes"):
        t.add_column(c, justify="left" if c in ("variant", "form") else "right")
    for r in rows:
        name = r["name"] + (" (default)" if r["default"] else "")
        t.add_row(name, r["form"], str(r["segments"]), str(r["degree"]), f"{r['float_max']:.2e}",
                  f"{r['float_rms']:.2e}", f"{r['int_max_lsb']:.2f}", f"{r['int_rms_lsb']:.3f}", str(r["mults"]),
                  str(r["bytes"]))
    console.print(t)
    for r in rows:
        console.print(f"  {r['name']}: {r['description']}")
    rep = activations.paper_report()
    console.print(f"seed 000's configuration ([0,1], (1,2], (2,3], (3,5.3], degree 5, least squares): our fit RMS "
                  f"{rep['fit_rms_0_5p3']:.3e} and max {rep['fit_max_0_5p3']:.3e} on [0, 5.3]; the paper's printed "
                  f"coefficients give RMS {rep['printed_rms_0_6']:.4e} on [0, 6] (published: {rep['published_rms']:.4e})")
