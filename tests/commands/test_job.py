"""`nnik job`'s summary table prints its cells as text: a machine without [dynamics] reads
"- (no [dynamics])", not "- (no )" (rich took the brackets for markup)."""

from __future__ import annotations

from pathlib import Path

from rich.console import Console

from nnik.commands.job import job_table
from nnik.job.open_loop import run_job
from nnik.report.job_summary import JOB_HEADER, job_row
from tests.bad_input import copy_run, tiny_run  # noqa: F401 (fixture)

JOBS = Path(__file__).resolve().parents[2] / "datasets" / "jobs"


def printed(table) -> str:
    c = Console(record=True, width=400, file=open("/dev/null", "w"))
    c.print(table)
    return c.export_text()


def test_job_table_prints_every_cell_as_it_is(tiny_run, tmp_path):  # noqa: F811
    run = copy_run(tiny_run, tmp_path / "run")
    res = run_job(run, JOBS / "l_path.gcode", use_chip=False)
    assert not res.get("dynamics")  # the galvo has no [dynamics]
    text = printed(job_table(res))
    assert "(no [dynamics])" in text and "(no )" not in text
    for h, v in zip(JOB_HEADER, job_row(res)):
        assert h in text and v in text, (h, v)


def test_the_job_console_prints_brackets_as_they_are():
    """Every other line `nnik job` prints (auto's "[motion] max_contour_um", a tool rule's reason)
    goes through the module's console: text, not markup."""
    from nnik.commands import job

    with job.console.capture() as cap:
        job.console.print("auto: zv (contour target 50.0 µm, [motion] max_contour_um)")
    assert "[motion] max_contour_um" in cap.get()
