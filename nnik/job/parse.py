"""Stage 1 of a job, parse: the G-code file read, checked and fitted to the machine.

JobRequest (what the command line asks) -> ParsedJob: the machine's firmware configuration for
this job (the scenario's [motion] and [tool] with --shaper, --seg-um, the tool rule, flavour and
frame), the lines the chip is sent, their line numbers in the file, and the file's summary.
Nothing here reads the model directory: the scenario comes in with the request.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from nnik.dynamics.shapers import KINDS
from nnik.errors import NnikError
from nnik.firmware.config import MachineConfig, default_machine
from nnik.firmware.gcode.job_input import JobOptions, prepare, read_job
from nnik.firmware.gcode.reader import sendable

SHAPER_CHOICES = ("none",) + KINDS + ("auto",)


@dataclass(frozen=True)
class JobRequest:
    """One job as asked: the G-code file, the scenario whose [motion], [dynamics] and [tool] it
    runs with (the model's as trained, or the TOML's), and the command line's options (shaper:
    none|zv|mzv|zvd|ei|...|auto over the scenario's; precompensate: the job rewritten offline for
    the belts; opts: flavour, tool, tool rule and frame)."""

    job: Path
    scenario: object
    seg_um: int | None = None
    shaper: str | None = None
    precompensate: bool = False
    opts: JobOptions = field(default_factory=JobOptions)

    @property
    def source(self) -> str:
        return str(self.job)


@dataclass(frozen=True)
class ParsedJob:
    request: JobRequest
    asked: str  # the compensation asked for: none, a shaper kind, auto or precompensated
    cfg: MachineConfig  # the firmware's configuration for this job (no shaper yet when auto/precompensated)
    lines: list[str]  # what the chip is sent
    line_of: list[int]  # the file's line number of each line sent
    summary: dict  # flavour, tool rule, extent, frame, noted words (job_input.prepare)

    @property
    def scenario(self):
        return self.request.scenario


def machine_for(scn, shaper: str | None, seg_um: int | None) -> MachineConfig:
    """default_machine(scn) with the command line's --shaper and --seg-um; bad values: one line."""
    try:
        cfg = default_machine(scn, shaper)
    except ValueError as exc:
        raise NnikError(str(exc), None, "--shaper" if shaper else "[motion]") from None
    if seg_um is not None:
        try:
            cfg = replace(cfg, seg_um=seg_um)
        except ValueError as exc:
            raise NnikError(str(exc), None, "--seg-um") from None
    return cfg


def parse(req: JobRequest) -> ParsedJob:
    """The request's options checked, the file read and prepared (NnikError: one line)."""
    scn, shaper, precompensate = req.scenario, req.shaper, req.precompensate
    if shaper is not None and shaper not in SHAPER_CHOICES:
        raise NnikError(f"unknown shaper {shaper!r}; choose one of {', '.join(SHAPER_CHOICES)}", None, "--shaper")
    asked = "precompensated" if precompensate else (shaper or (scn.motion or {}).get("shaper", "none"))
    if asked != "none" and not scn.dynamics and not getattr(scn, "shaper", None):
        where = "--precompensate" if precompensate else "--shaper" if shaper else "[motion] shaper"
        raise NnikError(f"{'precompensation' if precompensate else 'shaper ' + repr(asked)} needs a [dynamics] table "
                        f"(f_hz, zeta) in {scn.source}", None, where)
    cfg = machine_for(scn, "none" if asked in ("auto", "precompensated") else asked, req.seg_um)
    prep = prepare(read_job(req.job), cfg, req.opts, req.source)
    return ParsedJob(req, asked, prep.cfg, [sendable(ln).decode("latin-1") for ln in prep.lines], prep.line_of,
                     prep.summary)
