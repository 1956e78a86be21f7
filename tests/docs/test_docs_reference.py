"""The reference pages against the code they describe: docs/scenario_reference.md holds every key
the scenario check accepts (with its default), and docs/commands.md every subcommand and every
option that `nnik <command> --help` prints."""

from __future__ import annotations

import contextlib
import importlib
import io
import re
import tomllib

import pytest

from tests.conftest import ROOT
from tests.docs.scenario_keys import scenario_keys

DOCS = ROOT / "docs"


def sections(page: str) -> dict[str, str]:
    """'## heading' -> its text, up to the next '## ' heading."""
    parts = re.split(r"(?m)^## (.+)$", (DOCS / page).read_text())
    return {parts[i].strip(): parts[i + 1] for i in range(1, len(parts), 2)}


def key_rows(text: str) -> dict[str, list[str]]:
    """The table rows of a section whose first cell is a `key`: key -> its cells."""
    rows = {}
    for line in text.splitlines():
        m = re.match(r"\|\s*`([^`]+)`\s*\|(.*)\|\s*$", line)
        if m:
            rows[m.group(1)] = [c.strip() for c in m.group(2).split("|")]
    return rows


def shown_default(p) -> str:
    if p.required:
        return "required"
    d = p.default
    if d is None:
        return "unset"
    if isinstance(d, bool):
        return "true" if d else "false"
    if isinstance(d, str):
        return f'`"{d}"`'
    if isinstance(d, float):
        return f"{d:g}"
    if isinstance(d, tuple):
        return "[" + ", ".join(map(str, d)) + "]"
    return str(d)


def scenario_page_rows() -> dict[str, dict[str, list[str]]]:
    out = {}
    for heading, text in sections("scenario_reference.md").items():
        m = re.fullmatch(r"\[([\w.]+)\]", heading)
        name = m.group(1) if m else ("top" if heading == "Top level" else None)
        if name:
            out[name] = key_rows(text)
    return out


@pytest.mark.parametrize("section,key,param", scenario_keys(), ids=lambda v: v if isinstance(v, str) else "")
def test_every_scenario_key_is_on_the_reference_page_with_its_default(section, key, param):
    rows = scenario_page_rows()
    heading = "Top level" if section == "top" else f"[{section}]"
    assert section in rows, f"docs/scenario_reference.md has no '## {heading}' section"
    assert key in rows[section], f"docs/scenario_reference.md: [{section}] {key} is accepted but not listed"
    assert rows[section][key][0] == shown_default(param), \
        f"[{section}] {key}: the page says {rows[section][key][0]!r}, the code's default is {shown_default(param)!r}"


def test_the_reference_page_lists_no_key_the_scenario_refuses():
    accepted = {(s, k) for s, k, _ in scenario_keys()}
    listed = {(s, k) for s, rows in scenario_page_rows().items() for k in rows}
    assert listed - accepted == set()


def test_the_reference_pages_example_is_a_valid_scenario(tmp_path):
    from nnik.machine.scenario import Scenario

    block = re.search(r"## Example.*?```toml\n(.*?)```", (DOCS / "scenario_reference.md").read_text(), re.S).group(1)
    Scenario.from_dict(tomllib.loads(block), "example", tmp_path)


def nnik_main():
    """The console script's function, as pyproject.toml names it."""
    target = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]["nnik"]
    module, func = target.split(":")
    return getattr(importlib.import_module(module), func)


def help_text(*argv: str) -> str:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        try:
            code = nnik_main()([*argv, "--help"])
        except SystemExit as exc:  # argparse's own exit, where main lets it through
            code = exc.code
    assert code == 0, f"nnik {' '.join(argv)} --help exited {code}"
    return out.getvalue()


def subcommands() -> list[str]:
    m = re.search(r"\{([\w,-]+)\}", help_text())
    return m.group(1).split(",")


def options(help_: str) -> set[str]:
    """Every option string in an argparse help text (-o and --outdir alike), -h/--help aside."""
    found = set(re.findall(r"(?<![\w-])(--?[a-zA-Z][\w-]*)", help_.split("options:", 1)[-1]))
    return found - {"-h", "--help"}


def test_every_subcommand_has_its_section_on_the_command_page():
    heads = sections("commands.md")
    missing = [c for c in subcommands() if f"nnik {c}" not in heads]
    assert not missing, f"docs/commands.md has no '## nnik CMD' section for {missing}"


@pytest.mark.parametrize("command", subcommands())
def test_every_option_of_a_subcommand_is_in_its_section(command):
    text = sections("commands.md").get(f"nnik {command}", "")
    shown = set(re.findall(r"`(--?[a-zA-Z][\w-]*)", text))
    missing = sorted(options(help_text(command)) - shown)
    assert not missing, f"docs/commands.md, nnik {command}: options not described: {missing}"
