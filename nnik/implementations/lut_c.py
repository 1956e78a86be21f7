"""What the C template of the lut and hybrid families needs to know about a table."""

from __future__ import annotations

from nnik.implementations.c_common import c_list, i32


def table_ctx(problem: Problem, tab: Table) -> dict:
    """What the C template needs about the table."""
    rows = []
    n0, n1 = tab.grid.n
    for o in range(2):
        rows.append(c_list(tab.ent[o].ravel(), per_line=n0 if n0 <= 16 else 16))
    flipmask = [sum(1 << o for o in range(2) if tab.odd[o, a]) for a in range(2)]
    return {"tab": tab, "rows": rows, "ctype": f"int{tab.bits}_t",
            "rd": "NNIK_RD_I16" if tab.bits == 16 else "NNIK_RD_I32", "flipmask": flipmask,
            "origin": [i32(v) for v in tab.grid.origin],
            "oddtxt": [" and ".join(v for a, v in enumerate("xy") if tab.odd[o, a]) for o in range(2)]}
