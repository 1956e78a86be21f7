"""Rendering the sections: self-contained HTML (jinja2) and Markdown."""

from __future__ import annotations

import datetime as _dt
import html
import re
from pathlib import Path

from nnik.report.document import Section, Table

TEMPLATE = "report.html.j2"
TEMPLATE_DIR = Path(__file__).resolve().parents[1] / "templates"
_TICKS = re.compile(r"`([^`]+)`")


def _ticks_html(s: str):
    from markupsafe import Markup

    return Markup(_TICKS.sub(lambda mo: f"<code>{mo.group(1)}</code>", html.escape(str(s), quote=False)))


def render_html(sections: list[Section], metrics: dict) -> str:
    import jinja2

    env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATE_DIR)),
                             autoescape=jinja2.select_autoescape(["html", "j2"]), trim_blocks=True, lstrip_blocks=True,
                             undefined=jinja2.StrictUndefined)
    env.filters["ticks"] = _ticks_html
    from nnik import __version__

    return env.get_template(TEMPLATE).render(
        sections=sections, m=metrics, version=__version__,
        generated=_dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z"),
    )


def _md_escape(s: str) -> str:
    return str(s).replace("|", "\\|").replace("\n", " ")


def render_markdown(sections: list[Section], metrics: dict) -> str:
    out = [f"# nnik report: {metrics['name']}", ""]
    for sec in sections:
        out += [f"## {sec.title}", ""]
        if sec.figures_first:
            out += _md_figures(sec)
        for p in sec.paragraphs:
            out += [p, ""]
        for cls, v in sec.verdicts:
            out += [f"> {'**' if cls == 'bad' else ''}{v}{'**' if cls == 'bad' else ''}", ""]
        for n in sec.not_run:
            out += [f"> *{n}*", ""]
        for t in sec.tables:
            out += [f"**{t.title}**", ""]
            out.append("| " + " | ".join(_md_escape(h) for h in t.header) + " |")
            out.append("|" + "|".join("---:" if r else "---" for r in _numeric_columns(t)) + "|")
            carry: dict[int, int] = {}
            for row in t.rows:
                cells, it = [], iter(row)
                col = 0
                while col < len(t.header):
                    if carry.get(col, 0) > 0:
                        carry[col] -= 1
                        cells.append("")
                        col += 1
                        continue
                    c = next(it, None)
                    if c is None:
                        cells.append("")
                        col += 1
                        continue
                    cells.append(_md_escape(c.text))
                    if c.rowspan > 1:
                        carry[col] = c.rowspan - 1
                    cells += [""] * (c.colspan - 1)
                    col += c.colspan
                out.append("| " + " | ".join(cells) + " |")
            if t.note:
                out += ["", f"*{t.note}*"]
            out.append("")
        if not sec.figures_first:
            out += _md_figures(sec)
    return "\n".join(out).rstrip() + "\n"


def _md_figures(sec: Section) -> list[str]:
    out = []
    for f in sec.figures:
        out += [f"![{f.alt}]({f.file})", "", f"*{f.caption}*", ""]
    return out


def _numeric_columns(t: Table) -> list[bool]:
    """Per column: do most of its cells (in rows without spans) hold numbers?"""
    n = len(t.header)
    votes = [[0, 0] for _ in range(n)]
    for row in t.rows:
        if len(row) != n or any(c.colspan > 1 or c.rowspan > 1 for c in row):
            continue
        for i, c in enumerate(row):
            votes[i]["num" in c.cls.split()] += 1
    return [v[1] > v[0] for v in votes]
