"""The options every command spells and means the same way, defined once here.

- ``--quiet``: every command; nothing on stdout (warnings and the error line still go to stderr).
- ``--json``: a command that has a result; that result as one JSON object on stdout, nothing else.
- ``--seed``: the seed of a command's random draw, checked as the scenario's [dataset] seed.
- ``-o``: what the command writes, ``--outdir`` (a directory) or ``--output`` (a file), and its help
  says which.
- ``--target``: the chip (``avr``, ``pic18``), or ``host`` where the host runs the C alone.

``nnik.cli.main`` applies --quiet and --json (:func:`quiet_stdout`, :func:`json_text`) around every
command alike; tests/commands/test_common_options.py walks every parser to hold these rules.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys

from nnik.commands import option_types as opt
from nnik.implementations import FAMILIES as _FAMILIES

QUIET_HELP = "print nothing on stdout (warnings and the error line still go to stderr)"
JSON_HELP = "print the command's result as one JSON object on stdout, and nothing else there"
SEED_HELP = ("seed of {what} (an integer in the scenario's [dataset] seed range; the same seed gives the same "
             "{gives}; default {default})")
CHIPS = ("avr", "pic18")  # the simulated chips: avr-gcc + simavr, SDCC + gpsim
FAMILIES = tuple(_FAMILIES)  # the implementation families, as registered (--family's choices)
FAMILY_LIST = ", ".join(FAMILIES)


def add_command(sub, name: str, help: str, description: str | None = None, result: bool = False):
    """A subcommand's parser with the shared --quiet, and --json when it has a ``result``
    (its function returns the dict that --json prints)."""
    p = sub.add_parser(name, help=help, description=description or help[:1].upper() + help[1:] + ".")
    p.add_argument("--quiet", action="store_true", help=QUIET_HELP)
    if result:
        p.add_argument("--json", action="store_true", help=JSON_HELP)
    return p


def add_seed(p, what: str, gives: str, default: int = 0) -> None:
    p.add_argument("--seed", type=opt.SEED, default=default, help=SEED_HELP.format(what=what, gives=gives,
                                                                                    default=default))


def add_outdir(p, what: str, default: str, required: bool = False) -> None:
    """-o/--outdir: the directory the command writes (its help says "directory")."""
    p.add_argument("-o", "--outdir", required=required, metavar="DIR",
                   help=f"{what} (a directory; default {default})" if default else f"{what} (a directory)")


def add_output_file(p, what: str, default: str | None = None, required: bool = False) -> None:
    """-o/--output: the file the command writes (its help says "file")."""
    p.add_argument("-o", "--output", required=required, metavar="FILE",
                   help=f"{what} (a file; default {default})" if default else f"{what} (a file)")


def add_target(p, help: str, choices=CHIPS, default: str | None = None, required: bool = False) -> None:
    p.add_argument("--target", choices=choices, default=default, required=required, help=help)


def quiet(args) -> bool:
    return bool(getattr(args, "quiet", False) or getattr(args, "json", False))


def show_progress(args) -> bool:
    """Progress bars on stderr: on a terminal, unless --quiet or --json."""
    return sys.stderr.isatty() and not quiet(args)


@contextlib.contextmanager
def quiet_stdout(args):
    """With --quiet or --json the command's own lines and tables go nowhere."""
    if not quiet(args):
        yield
        return
    with open(os.devnull, "w") as null, contextlib.redirect_stdout(null):
        yield


def _plain(o):
    if hasattr(o, "tolist"):  # numpy arrays and scalars
        return o.tolist()
    return str(o)  # paths and the like


def json_text(result) -> str:
    return json.dumps(result if result is not None else {}, indent=2, default=_plain)
