"""Hostile conditions for the bad-input campaign, made with real operating-system errors: `nnik`
run as a subprocess under a file-size limit (EFBIG, unprivileged), on a small full tmpfs (ENOSPC,
root only), in a read-only place (EACCES by chmod, or EROFS by a read-only bind mount as root),
killed by SIGINT or SIGKILL while it works; and the checks that follow: one `nnik: error:` line,
no temporary file left, every output file that changed whole, nothing changed on a refusal."""

from __future__ import annotations

import contextlib
import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
IS_ROOT = os.geteuid() == 0


def nnik(argv, fsize: int | None = None, timeout: float = 600, cwd=None, env=None) -> subprocess.CompletedProcess:
    """`python -m nnik argv` in a subprocess, with RLIMIT_FSIZE = fsize bytes if given (a write
    past it fails with EFBIG; Python ignores SIGXFSZ, the compilers it starts get it)."""
    def limit():
        if fsize is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (fsize, fsize))

    e = {**os.environ, "PYTHONPATH": str(ROOT), "COLUMNS": "200", **(env or {})}
    return subprocess.run([sys.executable, "-m", "nnik", *map(str, argv)], capture_output=True, text=True,
                          timeout=timeout, preexec_fn=limit, cwd=cwd, env=e)


def one_error(proc: subprocess.CompletedProcess, *needles: str) -> str:
    """Exit 2 and exactly one `nnik: error:` line on stderr (warnings aside), no traceback."""
    err = proc.stderr
    assert "Traceback" not in err, err
    assert proc.returncode == 2, (proc.returncode, err[-2000:])
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("nnik: warning:")]
    assert len(lines) == 1 and lines[0].startswith("nnik: error: "), err
    for n in needles:
        assert n in lines[0], (n, lines[0])
    return lines[0]


def leftovers(d: Path) -> list[str]:
    """Temporary files and folders nnik's atomic writers make (none may stay behind)."""
    d = Path(d)
    for _ in range(20):  # a writer may remove a staging folder while the walk is inside it: walk again
        if not d.is_dir():
            return []
        try:
            return sorted(str(p.relative_to(d)) for p in d.rglob(".*") if ".tmp" in p.name or ".staging-" in p.name
                          or ".old-" in p.name)
        except FileNotFoundError:
            continue
    raise AssertionError(f"{d}: its temporary files kept vanishing under the walk")


def whole(p: Path) -> bool:
    """A file a later command could trust is complete for its kind (a torn write is not)."""
    data = p.read_bytes()
    suffix = p.suffix
    try:
        if suffix == ".json":
            json.loads(data)
        elif suffix in (".npz", ".pt"):
            with zipfile.ZipFile(p) as z:
                return z.testzip() is None
        elif suffix == ".png":
            return data.startswith(b"\x89PNG") and data.endswith(b"IEND\xaeB`\x82")
        elif suffix == ".onnx":
            import onnx

            onnx.load(str(p))
        elif suffix == ".html":
            return data.rstrip().endswith(b"</html>")
        elif suffix in (".csv", ".c", ".h", ".md", ".gcode", ".toml", ".ino", ".properties"):
            return data == b"" or data.endswith(b"\n")
    except Exception:  # noqa: BLE001 - unreadable is not whole
        return False
    return True


def snapshot(d: Path) -> dict:
    from tests.bad_input import snapshot as snap

    return snap(d)


def torn_files(d: Path, before: dict) -> list[str]:
    """Files under d that changed since ``before`` and are not whole."""
    d = Path(d)
    now = snapshot(d)
    return sorted(k for k, v in now.items() if v != "dir" and before.get(k) != v and not whole(d / k))


# ---- a full disk ---------------------------------------------------------------------------------
@contextlib.contextmanager
def small_tmpfs(size_kb: int):
    """A tmpfs of size_kb mounted on a new directory (root only: skips otherwise)."""
    if not IS_ROOT:
        pytest.skip("mounting a small tmpfs needs root (the file-size-limit tests cover the unprivileged case)")
    d = Path(tempfile.mkdtemp(prefix="nnik-tmpfs-"))
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size_kb}k", "tmpfs", str(d)], capture_output=True, text=True)
    if r.returncode:
        d.rmdir()
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.strip()}")
    try:
        yield d
    finally:
        subprocess.run(["umount", "-l", str(d)], check=False)
        d.rmdir()


def fill(d: Path, leave_bytes: int) -> None:
    """Fill the file system of d until about leave_bytes are free."""
    st = os.statvfs(d)
    free = st.f_bavail * st.f_frsize
    if free > leave_bytes:
        with open(Path(d) / ".filler", "wb") as f:
            with contextlib.suppress(OSError):
                f.write(b"\0" * (free - leave_bytes))


# ---- a read-only place ---------------------------------------------------------------------------
@contextlib.contextmanager
def read_only(d: Path):
    """d made read-only: chmod a-w for an ordinary user (EACCES); as root, whom modes do not stop,
    a read-only bind mount of d on itself (EROFS), or a skip where mounting is not allowed."""
    d = Path(d)
    if not IS_ROOT:
        modes = {p: p.stat().st_mode for p in [d, *d.rglob("*")] if p.is_dir()}
        for p in modes:
            p.chmod(modes[p] & ~0o222)
        try:
            yield d
        finally:
            for p, m in modes.items():
                p.chmod(m)
        return
    r = subprocess.run(["mount", "--bind", str(d), str(d)], capture_output=True, text=True)
    if r.returncode:
        pytest.skip(f"running as root (modes do not stop root) and cannot bind-mount read-only: {r.stderr.strip()}")
    try:
        r = subprocess.run(["mount", "-o", "remount,bind,ro", str(d)], capture_output=True, text=True)
        if r.returncode:
            pytest.skip(f"running as root (modes do not stop root) and cannot remount read-only: {r.stderr.strip()}")
        yield d
    finally:
        subprocess.run(["umount", "-l", str(d)], check=False)


# ---- a kill while it works -----------------------------------------------------------------------
def kill_during(argv, sig: int, when, cwd=None, limit: float = 600) -> str:
    """Start `nnik argv`; as soon as ``when()`` is true (e.g. a temporary file of an atomic write
    exists: the command is in the middle of a write), send sig to its process group. Returns
    "killed", or how it ended if it finished first."""
    e = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.Popen([sys.executable, "-m", "nnik", *map(str, argv)], stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE, text=True, start_new_session=True, cwd=cwd, env=e)
    try:
        t0 = time.monotonic()
        while not when():
            if p.poll() is not None:
                return f"ended by itself (exit {p.returncode})"
            assert time.monotonic() - t0 < limit, "the command never reached the point to kill it"
            time.sleep(0.001)
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, sig)
        try:
            p.wait(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
        err = p.stderr.read()
        assert "Traceback" not in err, err
        return "killed"
    finally:
        p.stderr.close()


def wait_for(cond, timeout: float = 120.0, what: str = "") -> None:
    t0 = time.monotonic()
    while not cond():
        assert time.monotonic() - t0 < timeout, f"timed out waiting for {what}"
        time.sleep(0.05)
