"""The report's G-code job section: "not run" until `nnik job` has run, then its table and PNG."""

from __future__ import annotations

from pathlib import Path

from nnik.job.open_loop import run_job
from nnik.report.job_summary import JOB_HEADER
from nnik.report import write_report
from tests.bad_input import copy_run, tiny_run  # noqa: F401 (fixture)
from tests.report.test_report import parse

JOBS = Path(__file__).resolve().parents[2] / "datasets" / "jobs"


def _section(index: Path) -> str:
    """The jobs section of report.md."""
    text = (index.parent / "report.md").read_text(encoding="utf-8")
    start = text.index("## G-code jobs")
    return text[start:text.index("\n## ", start + 1)]


def test_jobs_section_not_run_then_table_and_picture(tiny_run, tmp_path):
    run = copy_run(tiny_run, tmp_path / "run")
    assert "not run — run `nnik job OUTDIR JOB.gcode`" in _section(write_report(run))

    res = run_job(run, JOBS / "l_path.gcode", use_chip=False)
    index = write_report(run)
    parser, _ = parse(index)
    sec = _section(index)
    assert "nnik job OUTDIR" not in sec
    for h in JOB_HEADER:
        assert h in sec
    assert "job_l_path.png" in parser.imgs
    assert (index.parent / "job_l_path.png").read_bytes() == Path(res["png"]).read_bytes()
    # the row holds the job's own figures
    assert f"{res['contour_um']['max']:.1f} / {res['contour_um']['rms']:.1f}" in sec
    assert f"| {res['segments']} |" in sec and "not run (not asked)" in sec

    (run / "job" / "l_path.json").unlink()  # the job's results are gone: so is its picture
    assert "not run — run `nnik job" in _section(write_report(run))
    assert not (index.parent / "job_l_path.png").exists()
