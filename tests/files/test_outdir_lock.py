"""Two nnik commands writing into one directory: the second gets one line and exit 2."""

from __future__ import annotations

import subprocess
import sys
import time

from nnik.files.outdir import LOCK_FILE
from tests.bad_input import fails
from tests.conftest import DATASETS


def test_second_writer_is_refused(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    holder = subprocess.Popen([sys.executable, "-c",
                               "import sys, time; from nnik.files.outdir import hold_lock; hold_lock(sys.argv[1]); "
                               "print('held', flush=True); time.sleep(60)", str(out)],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        line = fails(capsys, ["generate", DATASETS / "galvo_cba2012.toml", "-o", out], "another nnik command",
                     f"pid {holder.pid}")
        assert "choose another -o" in line
        assert not (out / "data.npz").exists()
    finally:
        holder.kill()
        holder.wait()
    time.sleep(0.1)
    # the holder is gone: its lock went with it, and the directory is usable again
    from nnik.cli import main

    assert main(["generate", str(DATASETS / "galvo_cba2012.toml"), "-o", str(out)]) == 0
    assert (out / "data.npz").is_file() and not (out / LOCK_FILE).exists()
