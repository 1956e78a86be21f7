"""`nnik run --help` describes today's pipeline: every registered family fitted on one contract,
each family's best verified on the simulated chips, the cheapest that meets [target] picked."""

from __future__ import annotations

from nnik.cli import main
from nnik.implementations import FAMILIES


def help_text(capsys, *argv: str) -> str:
    capsys.readouterr()
    assert main([*argv, "--help"]) == 0
    return " ".join(capsys.readouterr().out.split())  # argparse's line breaks undone


def test_run_help_describes_the_families_and_the_pick(capsys):
    text = help_text(capsys, "run")
    for fam in FAMILIES:
        assert fam in text, fam
    for phrase in ("one contract", "simulated chips", "fewest cycles", "[target] max_error", "c/NAME.c",
                   "c/alt/<family>/", "nnik job"):
        assert phrase in text, phrase
    assert "generate, train, export and evaluate" not in text  # the MLP-only pipeline's words


def test_top_level_help_names_every_command_by_task(capsys):
    import argparse

    from nnik.cli import build_parser

    text = help_text(capsys)
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    tasks = text.split("commands by task:")[1]
    for name in sub.choices:
        assert name in tasks, f"{name} is in no task group of `nnik --help`"
    for fam in FAMILIES:
        assert fam in text
