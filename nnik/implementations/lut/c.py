"""What the C template of the lut and hybrid families needs to know about a table."""

from __future__ import annotations

from nnik.implementations.c_common import c_list, i32


def table_ctx(problem: Problem, tab: Table) -> dict:
    """What the C template needs about the table."""
    rows, toff = [], [0]
    n0, n1 = tab.grid.n
    for o in range(2):
        st = tab.stored(o)
        rows.append(c_list(st, per_line=n0 if n0 <= 16 and tab.dep[o] == "xy" else 16))
        toff.append(toff[-1] + st.size)
    flipmask = [sum(1 << o for o in range(2) if tab.odd[o, a]) for a in range(2)]
    return {"tab": tab, "rows": rows, "toff": toff[:2], "nent": toff[2], "dep": tab.dep, "ctype": f"int{tab.bits}_t",
            "rd": "NNIK_RD_I16" if tab.bits == 16 else "NNIK_RD_I32", "flipmask": flipmask,
            "origin": [i32(v) for v in tab.grid.origin],
            "oddtxt": [" and ".join(v for a, v in enumerate("xy") if tab.odd[o, a]) for o in range(2)]}
