"""The open-loop job (`nnik job`): the G-code through the firmware's logic in Python and on the
simulated Uno, stage by stage.

parse -> plan -> shape -> sample and IK -> chip co-simulation -> measure -> report. The Python
model gives every step (segment, tick, motor, direction) and the contour error; the chip (the
library's NAME_gcode sketch built with the Arduino AVR core, on simavr) must emit the same steps.
The chip's sketches are built while the Python model samples the job, and the job runs on simavr
while the picture is drawn. Reported: the job's time (planned with acceleration), the peak step
rate against the one-step-per-tick limit (and the samples that had to be stretched beyond it), and
on the chip the sample loop's share of the CPU (the busy pin's high time over the motion's time),
its cycles per sample, flash and SRAM. Results: OUTDIR/job/<job>.json and <job>.png.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

from nnik.errors import NnikError
from nnik.files.outdir import JOB_DIR
from nnik.firmware.gcode.chip import CLOCK_HZ
from nnik.firmware.gcode.job_input import JobOptions
from nnik.firmware.model_dir import ModelDir
from nnik.job import cosim
from nnik.job.kind import JobKind
from nnik.job.measure import compare_chip, measure
from nnik.job.parse import JobRequest, parse
from nnik.job.plan import check, plan
from nnik.job.report import picture, report
from nnik.job.sample import sample
from nnik.job.shape import shape
from nnik.progress import bar


@dataclass
class OpenLoopJob(JobKind):
    """use_chip None: on the simulated chip when the toolchain is there (mcu: the Uno's
    atmega328p or the Mega's atmega2560); check: parse and plan only (grbl's $C), no IK, no chip,
    nothing written; warn: called at once with each warning line; protocol: how the chip is sent
    the lines (chip.PROTOCOLS: grbl's character counting, as grbl senders stream, or send-response)."""

    use_chip: bool | None = None
    mcu: str = "atmega328p"
    check: bool = False
    warn: Callable[[str], None] | None = None
    protocol: str = "counting"
    name = "open loop"

    def run(self, model: ModelDir, request: JobRequest) -> dict:
        from nnik.firmware.gcode import chip

        parsed = parse(request)
        parsed = replace(parsed, cfg=replace(parsed.cfg, mcu=self.mcu))  # the chip's lookahead, the model's too
        if self.check:
            return check(parsed)
        ik = model.ik  # read here, before the chip's build thread shares it
        job_path = request.job
        # a long job shows its stage on a terminal (nothing in a log: nnik.progress)
        stages = bar(total=4, desc=f"job {job_path.name}", unit="stage", leave=False)
        out = model.path / JOB_DIR
        out.mkdir(parents=True, exist_ok=True)
        planned = plan(parsed)
        if parsed.scenario.dynamics:
            stages.set_postfix_str("the belts: every compensation on the tip")
        shaped = shape(planned, ik, out)
        stages.update(1)
        why = chip.tool_missing_reason()
        use = not (self.use_chip is False or (self.use_chip is None and why))
        if use and why:
            raise NnikError(f"avr: {why}")
        pool = ThreadPoolExecutor(max_workers=1) if use else None  # the chip's builds beside the model
        try:
            work = out / "work" / job_path.stem
            built = pool.submit(cosim.build, model, shaped.cfg, work, self.mcu) if use else None
            stages.set_postfix_str("Python model of the firmware")
            sampled = sample(shaped, ik)
            stages.update(1)
            measured = measure(sampled, self.warn)
            chip_figures = {"not_run": "not asked" if self.use_chip is False else why}
            if use:
                seconds = measured.seconds
                stages.set_postfix_str(f"simulated {'Mega' if self.mcu == 'atmega2560' else 'Uno'} "
                                       f"({seconds:.1f} s of motion)")
                sim = bar(total=round(seconds, 1), desc="chip", unit="s", leave=False, position=1,
                          bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} s simulated [{elapsed}<{remaining}]")

                def progress(_answers: int, cycle: int) -> None:
                    sim.update(max(0.0, min(cycle / CLOCK_HZ, seconds) - sim.n))

                ran = pool.submit(lambda: cosim.run(built.result(), shaped, seconds, progress, self.protocol))
            stages.set_postfix_str("plot")
            png = picture(measured, out)
            stages.update(1)
            if use:
                co = ran.result()
                sim.close()
                chip_figures = compare_chip(co, measured, out)
            stages.update(1)
        finally:
            if pool is not None:
                pool.shutdown(wait=True, cancel_futures=True)
        res = report(measured, chip_figures, png, out)
        stages.close()
        return res


def run_job(outdir: Path, job_path: Path, seg_um: int | None = None, use_chip: bool | None = None,
            shaper: str | None = None, precompensate: bool = False, opts: JobOptions | None = None,
            check: bool = False, mcu: str = "atmega328p", scenario=None, warn=None,
            model: ModelDir | None = None, protocol: str = "counting") -> dict:
    """An open-loop job on OUTDIR (read once here, or given as model): see OpenLoopJob and
    JobRequest. scenario: the machine's [motion], [dynamics] and [tool] (default: the model's, as
    it was trained; `nnik job SCENARIO.toml` gives the TOML's)."""
    model = model if model is not None else ModelDir.load(Path(outdir))
    req = JobRequest(Path(job_path), scenario if scenario is not None else model.scenario, seg_um, shaper,
                     precompensate, opts or JobOptions())
    return OpenLoopJob(use_chip, mcu, check, warn, protocol).run(model, req)
