#!/usr/bin/env bash
# Install the simulator toolchains nnik verifies generated C on.
#
#   AVR   : gcc-avr, avr-libc, simavr                (Debian packages)
#   Uno   : arduino-core-avr, arduino-mk, libsimavr-dev (Debian packages: the Arduino AVR core
#           the G-code sketches build on, and the simavr library the job harness links)
#   PIC18 : gputils, gpsim                           (Debian packages)
#           SDCC 4.2.0 with the pic16 port only      (built here from Debian's own
#                                                     source package sdcc 4.2.0+dfsg-1,
#                                                     because Debian's binary sdcc has no PIC ports)
#
# Everything that is not a Debian package goes under ONE prefix:
#   ${NNIK_TOOLCHAIN_PREFIX:-/opt/nnik-toolchains}
#     sdcc/bin/sdcc, sdcc/bin/sdcpp, sdcc/share/sdcc/include/{,pic16}   the compiler
#     pic16/libsdcc.lib  pic16/libm18f.lib  pic16/crt0i.o             the pic16 runtime
#     pic16/pic18f452_sfr.o                                            core SFR definitions
#     BUILD_INFO                                                       versions + step timings
#
# Idempotent: apt packages already installed are skipped, and the SDCC build is skipped
# when the prefix already holds a complete install (set NNIK_TOOLCHAIN_FORCE=1 to rebuild).
# Needs root (or sudo) for apt-get.  The build happens in a temporary directory that is
# removed afterwards; set NNIK_KEEP_BUILD=1 to keep it for debugging.
set -euo pipefail

PREFIX="$(realpath -m "${NNIK_TOOLCHAIN_PREFIX:-/opt/nnik-toolchains}")"
SDCC_DEB_VERSION="4.2.0+dfsg-1"
SDCC_UPSTREAM="4.2.0"
JOBS="${NNIK_BUILD_JOBS:-$(nproc 2>/dev/null || echo 2)}"
REPO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SFR_SRC="$REPO_ROOT/codegen/harness/pic18/pic18f452_sfr.c"

APT_PKGS=(gcc-avr avr-libc simavr gputils gpsim arduino-core-avr arduino-mk libsimavr-dev postgresql)
SDCC_BUILD_DEPS=(bison flex libboost-dev texinfo zlib1g-dev g++ make xz-utils ca-certificates)

T_START=$(date +%s)
STEP_LOG=()

log()  { printf '[install_toolchains] %s\n' "$*" >&2; }
die()  { printf '[install_toolchains] ERROR: %s\n' "$*" >&2; exit 1; }
step_done() { # name start_epoch
    local dt=$(( $(date +%s) - $2 ))
    STEP_LOG+=("$1: ${dt}s")
    log "step '$1' took ${dt}s"
}

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
        die "must run as root (or have sudo) to install Debian packages"; fi
fi
export DEBIAN_FRONTEND=noninteractive

# ---------------------------------------------------------------- 1. apt packages
missing_pkgs() {
    local p
    for p in "$@"; do
        if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
            printf '%s\n' "$p"
        fi
    done
}

sdcc_complete() {
    [ -x "$PREFIX/sdcc/bin/sdcc" ] && [ -x "$PREFIX/sdcc/bin/sdcpp" ] \
        && [ -f "$PREFIX/pic16/libsdcc.lib" ] && [ -f "$PREFIX/pic16/crt0i.o" ] \
        && [ -f "$PREFIX/pic16/libm18f.lib" ] && [ -f "$PREFIX/pic16/pic18f452_sfr.o" ] \
        && [ -f "$PREFIX/BUILD_INFO" ] \
        && "$PREFIX/sdcc/bin/sdcc" --version 2>/dev/null | grep -q "$SDCC_UPSTREAM"
}

NEED_SDCC=1
if [ "${NNIK_TOOLCHAIN_FORCE:-0}" != "1" ] && sdcc_complete; then
    NEED_SDCC=0
fi

want=("${APT_PKGS[@]}")
if [ "$NEED_SDCC" = 1 ]; then want+=("${SDCC_BUILD_DEPS[@]}"); fi
mapfile -t MISSING < <(missing_pkgs "${want[@]}")

t=$(date +%s)
if [ "${#MISSING[@]}" -gt 0 ]; then
    log "installing Debian packages: ${MISSING[*]}"
    $SUDO apt-get update -qq || die "apt-get update failed"
    $SUDO apt-get install -y -qq --no-install-recommends "${MISSING[@]}" >/dev/null \
        || die "apt-get install ${MISSING[*]} failed"
else
    log "Debian packages already present: ${want[*]}"
fi
step_done "apt packages" "$t"

if [ "$NEED_SDCC" = 0 ]; then
    log "SDCC pic16 already installed under $PREFIX ($("$PREFIX/sdcc/bin/sdcc" --version | head -n1))"
    log "nothing to do (NNIK_TOOLCHAIN_FORCE=1 rebuilds); total $(( $(date +%s) - T_START ))s"
    exit 0
fi

[ -f "$SFR_SRC" ] || die "missing $SFR_SRC (run this script from a checkout of nnik)"

# ---------------------------------------------------------------- 2. fetch Debian source of sdcc
BUILD="$(mktemp -d "${TMPDIR:-/tmp}/nnik-sdcc-build.XXXXXX")"
cleanup() {
    if [ "${NNIK_KEEP_BUILD:-0}" = "1" ]; then log "build dir kept: $BUILD"; else rm -rf "$BUILD"; fi
}
trap cleanup EXIT
chmod 755 "$BUILD"

t=$(date +%s)
APTDIR="$BUILD/apt"
mkdir -p "$APTDIR/lists/partial" "$APTDIR/cache/archives/partial" "$APTDIR/src"
SRCLIST="$APTDIR/nnik-src.sources"
# Derive deb-src stanzas from the machine's own apt configuration (deb822 *.sources files and
# one-line sources.list / *.list), keeping URIs, suites, components and Signed-By.  Only
# stanzas for this release's suites are kept (third-party repositories rarely carry sources).
python3 - "$SRCLIST" <<'PY' || die "could not derive deb-src entries from the apt sources"
import glob, os, re, sys
out = sys.argv[1]
codename = ""
try:
    for line in open("/etc/os-release"):
        if line.startswith("VERSION_CODENAME="):
            codename = line.split("=", 1)[1].strip().strip('"')
except OSError:
    pass

def suite_ok(s):
    return not codename or s == codename or s.startswith(codename + "-") or s.startswith(codename + "/")

entries = []  # (uris, suites, comps, signed_by)
def add(uris, suites, comps, signed):
    suites = [s for s in suites if suite_ok(s)]
    if uris and suites:
        entries.append((uris, suites, comps, signed))

for f in sorted(glob.glob("/etc/apt/sources.list.d/*.sources")):
    text = open(f).read()
    for stanza in re.split(r"\n\s*\n", text):
        fields, key = {}, None
        for line in stanza.splitlines():
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            if line[0] in " \t" and key:
                fields[key] += "\n" + line.strip()
                continue
            if ":" in line:
                key, val = line.split(":", 1)
                key = key.strip().lower()
                fields[key] = val.strip()
        if not fields or fields.get("enabled", "yes").lower() == "no":
            continue
        if "deb" not in fields.get("types", "").split():
            continue
        add(fields.get("uris", "").split(), fields.get("suites", "").split(),
            fields.get("components", "").split(), fields.get("signed-by", ""))

lists = ["/etc/apt/sources.list"] + sorted(glob.glob("/etc/apt/sources.list.d/*.list"))
for f in lists:
    if not os.path.isfile(f):
        continue
    for line in open(f):
        line = line.split("#", 1)[0].strip()
        if not line.startswith("deb "):
            continue
        opts = {}
        m = re.match(r"deb\s+\[([^\]]*)\]\s+(.*)", line)
        rest = line[4:].strip()
        if m:
            for o in m.group(1).split():
                if "=" in o:
                    k, v = o.split("=", 1)
                    opts[k.lower()] = v
            rest = m.group(2)
        parts = rest.split()
        if len(parts) < 2:
            continue
        add([parts[0]], [parts[1]], parts[2:], opts.get("signed-by", ""))

if not entries:
    sys.exit("no usable deb entries for release %r" % codename)
with open(out, "w") as fh:
    for uris, suites, comps, signed in entries:
        fh.write("Types: deb-src\nURIs: %s\nSuites: %s\n" % (" ".join(uris), " ".join(suites)))
        if comps:
            fh.write("Components: %s\n" % " ".join(comps))
        if signed:
            if "\n" in signed:  # inline key block
                fh.write("Signed-By: %s\n" % signed.replace("\n", "\n "))
            else:
                fh.write("Signed-By: %s\n" % signed)
        fh.write("\n")
print("derived %d deb-src stanza(s)" % len(entries), file=sys.stderr)
PY
# apt drops privileges to _apt for downloads: let it write to the private dirs.
if id _apt >/dev/null 2>&1; then chown -R _apt "$APTDIR/lists/partial" "$APTDIR/cache/archives/partial" "$APTDIR/src" 2>/dev/null || true; fi
APT_PRIV=(-o "Dir::Etc::SourceList=$SRCLIST" -o "Dir::Etc::SourceParts=/dev/null"
          -o "Dir::State::Lists=$APTDIR/lists" -o "Dir::Cache=$APTDIR/cache"
          -o "Dir::Cache::pkgcache=$APTDIR/cache/pkgcache.bin"
          -o "Dir::Cache::srcpkgcache=$APTDIR/cache/srcpkgcache.bin")
$SUDO apt-get "${APT_PRIV[@]}" update -qq >"$APTDIR/update.log" 2>&1 \
    || { cat "$APTDIR/update.log" >&2; log "apt-get update of the private deb-src list reported errors; trying anyway"; }
( cd "$APTDIR/src" && $SUDO apt-get "${APT_PRIV[@]}" source --download-only -qq "sdcc=$SDCC_DEB_VERSION" ) \
    >"$APTDIR/source.log" 2>&1 \
    || { cat "$APTDIR/update.log" "$APTDIR/source.log" >&2; die "apt-get source --download-only sdcc=$SDCC_DEB_VERSION failed"; }
ORIG="$(ls "$APTDIR"/src/sdcc_*.orig.tar.* 2>/dev/null | head -n1 || true)"
[ -n "$ORIG" ] || die "sdcc orig tarball not found after apt-get source"
log "downloaded $(basename "$ORIG") ($(du -h "$ORIG" | cut -f1))"
step_done "download sdcc source" "$t"

# ---------------------------------------------------------------- 3. unpack + configure + build compiler
t=$(date +%s)
mkdir -p "$BUILD/src"
tar -xf "$ORIG" -C "$BUILD/src"
SRC="$(find "$BUILD/src" -mindepth 1 -maxdepth 1 -type d | head -n1)"
[ -f "$SRC/configure" ] || die "unexpected layout of $(basename "$ORIG")"
step_done "unpack" "$t"

t=$(date +%s)
DISABLE=()
for p in mcs51 z80 z180 r2k r2ka r3ka sm83 tlcs90 ez80_z80 z80n ds390 ds400 pic14 hc08 s08 stm8 \
         pdk13 pdk14 pdk15 mos6502; do
    DISABLE+=("--disable-$p-port")
done
( cd "$SRC" && ./configure --prefix="$PREFIX/sdcc" "${DISABLE[@]}" --enable-pic16-port \
      --disable-ucsim --disable-sdcdb --disable-non-free ) >"$BUILD/configure.log" 2>&1 \
    || { tail -n 40 "$BUILD/configure.log" >&2; die "SDCC configure failed (log above)"; }
step_done "configure sdcc" "$t"

t=$(date +%s)
log "building SDCC (pic16 port) with make -j$JOBS; this takes 2-5 min on 2 cores"
# The top-level make builds the compiler, the preprocessor and then the device libraries;
# the last part fails because Debian strips the non-free PIC headers.  So build the parts
# we need explicitly and judge success by the binaries.
( cd "$SRC" && make -j"$JOBS" -C support/cpp && make -j"$JOBS" -C src ) >"$BUILD/make.log" 2>&1 \
    || { tail -n 60 "$BUILD/make.log" >&2; die "SDCC compiler build failed (last lines of make output above)"; }
[ -x "$SRC/bin/sdcc" ] || { tail -n 60 "$BUILD/make.log" >&2; die "SDCC compiler build produced no bin/sdcc"; }
[ -x "$SRC/bin/sdcpp" ] || die "SDCC build produced no bin/sdcpp"
step_done "build sdcc compiler" "$t"

# ---------------------------------------------------------------- 4. install compiler + headers
# Everything is staged under $BUILD/stage and moved into $PREFIX only at the end, so a
# failed build leaves a previous install intact.  (sdcc finds its headers relative to
# its own binary, bin/../share/sdcc/include, so the staged compiler works as is.)
t=$(date +%s)
STAGE="$BUILD/stage"
SP="$STAGE$PREFIX"
( cd "$SRC" && make -C src install DESTDIR="$STAGE" && make -C support/cpp install DESTDIR="$STAGE" ) \
    >"$BUILD/install.log" 2>&1 || { tail -n 40 "$BUILD/install.log" >&2; die "SDCC install failed"; }
INC="$SP/sdcc/share/sdcc/include"
mkdir -p "$INC"
# the free headers (generic, pic16/, asm/ ...); the non-free pic18fXXXX.h device headers are absent
cp -r "$SRC/device/include/." "$INC/"
find "$INC" \( -name 'Makefile*' -o -name '*.in' -o -name '*.mk' \) -type f -delete
# the pic16 port reads its device database (pic16devices.txt) from the include path
PDEV="$(find "$SRC/device" "$SRC/src/pic16" -name pic16devices.txt 2>/dev/null | head -n1)"
[ -n "$PDEV" ] || die "pic16devices.txt not found in the SDCC source"
cp "$PDEV" "$INC/pic16/"
"$SP/sdcc/bin/sdcc" --version >/dev/null 2>&1 || die "installed sdcc does not run"
step_done "install sdcc" "$t"

# ---------------------------------------------------------------- 5. pic16 runtime library
t=$(date +%s)
LIB="$BUILD/lib"
mkdir -p "$LIB/libsdcc" "$LIB/libm" "$SP/pic16"
SDCC="$SP/sdcc/bin/sdcc"
CFLAGS=(-mpic16 -p18f452 --use-non-free -I "$SRC/device/include/pic16" -I "$SRC/device/include")
fails=0
compile_dir() { # outdir files...
    local out="$1"; shift
    local f base
    for f in "$@"; do
        base="$(basename "$(dirname "$f")")_$(basename "${f%.c}")"
        # relative -o: gplink copies the .asm path into .cod files (truncated to 63 chars)
        if ! ( cd "$out" && "$SDCC" "${CFLAGS[@]}" -c "$f" -o "$base.o" ) >>"$BUILD/lib.log" 2>&1; then
            echo "FAILED: $f" >>"$BUILD/lib.log"; fails=$((fails + 1))
        fi
    done
}
compile_dir "$LIB/libsdcc" "$SRC"/device/lib/pic16/libsdcc/*/*.c
compile_dir "$LIB/libm" "$SRC"/device/lib/pic16/libm/*.c
( cd "$LIB" && "$SDCC" "${CFLAGS[@]}" -c "$SRC/device/lib/pic16/startup/crt0i.c" -o crt0i.o ) \
    >>"$BUILD/lib.log" 2>&1 || { tail -n 30 "$BUILD/lib.log" >&2; die "could not compile crt0i.c"; }
cp "$LIB/crt0i.o" "$SP/pic16/crt0i.o"
if [ "$fails" -gt 0 ]; then
    grep FAILED "$BUILD/lib.log" >&2
    die "$fails pic16 runtime source(s) failed to compile (see above)"
fi
# gplib: archive (one call per library; the .lib is what gplink searches)
( cd "$LIB/libsdcc" && gplib -c "$SP/pic16/libsdcc.lib" ./*.o ) || die "gplib libsdcc failed"
( cd "$LIB/libm" && gplib -c "$SP/pic16/libm18f.lib" ./*.o ) || die "gplib libm failed"
( cd "$LIB" && "$SDCC" -mpic16 -p18f452 --use-non-free -c "$SFR_SRC" -o pic18f452_sfr.o ) \
    >>"$BUILD/lib.log" 2>&1 || { tail -n 20 "$BUILD/lib.log" >&2; die "could not compile $SFR_SRC"; }
cp "$LIB/pic18f452_sfr.o" "$SFR_SRC" "$SP/pic16/"
n_sdcc=$(ls "$LIB"/libsdcc/*.o | wc -l); n_m=$(ls "$LIB"/libm/*.o | wc -l)
log "pic16 runtime: libsdcc.lib ($n_sdcc objects), libm18f.lib ($n_m objects), crt0i.o"
step_done "pic16 runtime library" "$t"

# ---------------------------------------------------------------- 6. move into place + record
mkdir -p "$PREFIX" || die "cannot create $PREFIX (set NNIK_TOOLCHAIN_PREFIX to a writable directory)"
rm -rf "$PREFIX/sdcc" "$PREFIX/pic16" "$PREFIX/BUILD_INFO"
mv "$SP/sdcc" "$SP/pic16" "$PREFIX/" || die "cannot move the build into $PREFIX"
SDCC="$PREFIX/sdcc/bin/sdcc"
"$SDCC" --version >/dev/null 2>&1 || die "installed sdcc does not run from $PREFIX"
TOTAL=$(( $(date +%s) - T_START ))
{
    echo "prefix: $PREFIX"
    echo "sdcc: $("$SDCC" --version 2>&1 | head -n1)"
    echo "sdcc_source: sdcc $SDCC_DEB_VERSION (Debian source package)"
    echo "gputils: $(gpasm -v 2>&1 | head -n1)"
    echo "gpsim: $(dpkg-query -W -f='${Version}' gpsim 2>/dev/null)"
    echo "gcc-avr: $(avr-gcc -dumpversion 2>/dev/null)"
    echo "simavr: $(dpkg-query -W -f='${Version}' simavr 2>/dev/null)"
    echo "built: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
    for s in "${STEP_LOG[@]}"; do echo "step: $s"; done
    echo "total_seconds: $TOTAL"
} >"$PREFIX/BUILD_INFO"
log "done in ${TOTAL}s:"
for s in "${STEP_LOG[@]}"; do log "  $s"; done
log "installed under $PREFIX (see $PREFIX/BUILD_INFO)"
