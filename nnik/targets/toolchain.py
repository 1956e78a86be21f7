"""Locate the simulator toolchains and run their commands.

AVR tools (avr-gcc, avr-size, avr-nm, simavr) come from Debian packages and are
looked up on PATH.  The PIC18 tools are gputils (gplink, gplib) and gpsim from
Debian, plus SDCC with its pic16 port, which ``scripts/install_toolchains.sh``
builds under one prefix:

    $NNIK_TOOLCHAIN_PREFIX (default /opt/nnik-toolchains)
        sdcc/bin/sdcc            compiler (its headers under sdcc/share/sdcc/include)
        pic16/libsdcc.lib        pic16 runtime support
        pic16/libm18f.lib        pic16 float math library
        pic16/crt0i.o            start-up code (linked first)

Tools are searched under the prefix first, then on PATH.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

DEFAULT_PREFIX = Path("/opt/nnik-toolchains")
REPO_ROOT = Path(__file__).resolve().parents[2]
HARNESS_DIR = REPO_ROOT / "codegen" / "harness"
INSTALL_HINT = "run scripts/install_toolchains.sh"

TARGETS = ("avr", "pic18")

AVR_TOOLS = ("avr-gcc", "avr-size", "avr-nm", "simavr")
PIC18_TOOLS = ("sdcc", "gplink", "gplib", "gpsim")
PIC18_LINKER_SCRIPT = Path("/usr/share/gputils/lkr/18f452_g.lkr")


class TargetError(RuntimeError):
    """A build or simulation on a target failed (one-line message)."""


def prefix() -> Path:
    """Install prefix of the non-Debian toolchain parts."""
    env = os.environ.get("NNIK_TOOLCHAIN_PREFIX")
    return Path(env) if env else DEFAULT_PREFIX


def find_tool(name: str) -> Optional[str]:
    """Full path of a tool: under the prefix first, then on PATH; None if absent."""
    p = prefix()
    for d in (p / "sdcc" / "bin", p / "bin"):
        cand = d / name
        if cand.is_file() and os.access(cand, os.X_OK):
            return str(cand)
    found = shutil.which(name)
    if name == "sdcc" and found and not _sdcc_has_pic16(found):
        return None  # e.g. Debian's binary sdcc, built without PIC ports
    return found


def _sdcc_has_pic16(path: str) -> bool:
    try:
        out = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return False
    return "pic16" in (out.stdout + out.stderr)


def pic16_runtime() -> Dict[str, Path]:
    """Paths of the pic16 runtime pieces built by install_toolchains.sh."""
    p = prefix() / "pic16"
    return {
        "crt0i": p / "crt0i.o",
        "libsdcc": p / "libsdcc.lib",
        "libm": p / "libm18f.lib",
        "linker_script": PIC18_LINKER_SCRIPT,
    }


def available(target: str) -> Tuple[bool, str]:
    """(True, "") if every tool the target needs is present, else (False, reason)."""
    if target not in TARGETS:
        return False, f"unknown target {target!r} (known: {', '.join(TARGETS)})"
    tools = AVR_TOOLS if target == "avr" else PIC18_TOOLS
    missing = [t for t in tools if find_tool(t) is None]
    if target == "pic18":
        for key, path in pic16_runtime().items():
            if not path.is_file():
                missing.append(str(path))
    if missing:
        where = f" (prefix {prefix()})" if target == "pic18" else ""
        return False, f"{target} toolchain incomplete, missing: {', '.join(missing)}{where}; {INSTALL_HINT}"
    return True, ""


def require(target: str) -> None:
    ok, why = available(target)
    if not ok:
        raise TargetError(why)


def tool_version(name: str) -> str:
    """First line of the tool's version output."""
    exe = find_tool(name)
    if exe is None:
        return f"{name} (not found)"
    flag = "--version"
    try:
        out = subprocess.run([exe, flag], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError) as e:  # pragma: no cover
        return f"{name} ({e})"
    text = (out.stdout or out.stderr).strip().splitlines()
    return text[0].strip() if text else name


def first_error_line(text: str) -> str:
    """The most informative single line of a tool's output."""
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    for pat in (r"\berror\b", r"\bERROR\b", r"undefined", r"not found", r"fatal"):
        for ln in lines:
            if re.search(pat, ln, re.IGNORECASE if pat.islower() else 0):
                return ln
    return lines[-1] if lines else "(no output)"


def run(cmd: Sequence[str], what: str, cwd: Optional[Path] = None, timeout: float = 600,
        log: Optional[Path] = None, stdin=subprocess.DEVNULL) -> subprocess.CompletedProcess:
    """Run a command; raise TargetError with a one-line message on failure or timeout."""
    cmd = [str(c) for c in cmd]
    try:
        res = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout,
                             stdin=stdin, errors="replace")
    except subprocess.TimeoutExpired as e:
        out = (e.stdout or b"")
        if log is not None:
            log.write_text(out.decode(errors="replace") if isinstance(out, bytes) else str(out))
        raise TargetError(f"{what}: timed out after {timeout:.0f}s") from None
    except OSError as e:
        raise TargetError(f"{what}: cannot run {cmd[0]}: {e}") from None
    if log is not None:
        log.write_text(f"$ {' '.join(cmd)}\n{res.stdout}\n{res.stderr}")
    if res.returncode != 0:
        hint = f" (log: {log})" if log is not None else ""
        raise TargetError(f"{what} failed: {first_error_line(res.stderr + res.stdout)}{hint}")
    return res


# ---------------------------------------------------------------- shared harness helpers

def c_ident(name: str) -> str:
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name or ""):
        raise TargetError(f"name {name!r} is not a C identifier")
    return name


def _c_int32(v: int) -> str:
    v = int(v)
    if v == -(2 ** 31):
        return "(-2147483647L - 1)"
    return f"{v}L"


def write_harness_inputs(dirpath: Path, name: str, vectors, n_out: int) -> None:
    """Write nnik_harness_cfg.h and nnik_vectors.inc for the harness templates."""
    import numpy as np

    vec = np.asarray(vectors, dtype=np.int64)
    if vec.ndim != 2 or vec.shape[0] < 1:
        raise TargetError(f"vectors must have shape (N, n_in) with N >= 1, got {vec.shape}")
    if vec.min() < -(2 ** 31) or vec.max() > 2 ** 31 - 1:
        raise TargetError("vectors do not fit in int32")
    n, n_in = vec.shape
    dirpath.mkdir(parents=True, exist_ok=True)
    cfg = (
        "/* generated by nnik.targets: harness configuration */\n"
        "#ifndef NNIK_HARNESS_CFG_H\n#define NNIK_HARNESS_CFG_H\n"
        "#include <stdint.h>\n"
        f"#define NNIK_N_VEC {n}\n#define NNIK_N_IN {n_in}\n#define NNIK_N_OUT {n_out}\n"
        f"#define NNIK_IK {name}_ik\n"
        f"int8_t {name}_ik(const int32_t in_um[{n_in}], int32_t out[{n_out}]);\n"
        "#endif\n"
    )
    (dirpath / "nnik_harness_cfg.h").write_text(cfg)
    rows = "\n".join("{ " + ", ".join(_c_int32(x) for x in row) + " }," for row in vec.tolist())
    (dirpath / "nnik_vectors.inc").write_text("/* generated by nnik.targets */\n" + rows + "\n")


def to_int32(u: int) -> int:
    u &= 0xFFFFFFFF
    return u - (1 << 32) if u & 0x80000000 else u


def progress_bar(total: int, desc: str, enabled: Optional[bool]):
    """A bar over simulator vectors: on a terminal unless `enabled` is False (nnik.progress)."""
    from nnik.progress import bar

    return bar(total=total, desc=desc, unit="vec", disable=enabled is False, leave=False)


def split_batches(n: int, batch_size: int) -> List[Tuple[int, int]]:
    batch_size = max(1, int(batch_size))
    return [(s, min(n, s + batch_size)) for s in range(0, n, batch_size)]
