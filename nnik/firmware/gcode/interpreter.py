"""The interpreter of nnik_gcode.c in Python: a line's words -> modal state, coordinates and
planner operations, bit for bit with the chip, and grbl 1.1's meaning for every word it shares.

Positions are machine micrometres less the work origin (``mp``: X, Y and the tool's Z). A target
in absolute mode is the value plus the work offset of the active system (G54..G59, set by G10),
the G92 offset and, for Z, the tool length offset (G43.1); G53 takes machine values; G91 adds to
the position. Every block end passes the job's frame transform (``--fit``, ``--scale``,
``--offset``: p * scale / 2^16 + shift, rounded half up) before the planner sees it.
"""

from __future__ import annotations

from math import isqrt

from nnik.firmware.config import SCALE_ONE, MachineConfig
from nnik.firmware.gcode.codes import GcodeAlarm, GcodeLineError, describe
from nnik.firmware.gcode import curves
from nnik.firmware.gcode.geometry import chord_length
from nnik.firmware.gcode.parse import Block, parse_block
from nnik.firmware.gcode.planner import Planner, length_q
from nnik.firmware.gcode.planner_arc import as_arc_op
from nnik.firmware.gcode.program import MIN_FEED, POS_LIMIT, TOOL_SCALED, Move, Plan
from nnik.firmware.gcode.reader import DOLLAR, EMPTY, ERROR, read_line, sendable

DWELL_MS_MAX = (1 << 24) - 1


class Interpreter:
    """The state of nnik_gc_t without the IK: positions, offsets, modes, feed, tool."""

    def __init__(self, cfg: MachineConfig):
        self.cfg = cfg
        self.mp = [0, 0, 0]  # machine position, um
        self.coord = [[0, 0, 0] for _ in range(6)]  # G54..G59
        self.g92 = [0, 0, 0]
        self.tlo = 0
        self.home = [[0, 0, cfg.z_home_um], [0, 0, cfg.z_home_um]]  # G28, G30
        self.wcs = 0
        self.motion, self.plane, self.inch, self.relative, self.arc_abs, self.inverse = 0, 0, False, False, False, False
        self.feed = cfg.feed_um_min
        self.spindle, self.s, self.coolant, self.tool_no = 0, 0, 0, 0
        self.e, self.e_rel, self.pen = 0, False, False  # Marlin's E (um) and its mode; M300's pen
        self.tool = self.last_tool = 0
        self.alarm = 0
        self.bezier_c2: tuple[int, int] | None = None  # the last G5's second control point
        self.line_no = 0
        self.plan = Plan()
        self.notes: dict[str, int] = {}
        self.last_wins = 0
        self.moves_on = self.moves_off = 0
        self.features_used: set[str] = set()  # build options the job's words need
        self.z_seen: list[int] = []  # the Z (work) of every move: a laser's focus, a pen's heights

    # ---- frames -----------------------------------------------------------------------------
    def wco(self, k: int, wcs: int | None = None, tlo: int | None = None) -> int:
        """Work offset of axis k: machine = work + wco."""
        w = self.wcs if wcs is None else wcs
        return self.coord[w][k] + self.g92[k] + ((self.tlo if tlo is None else tlo) if k == 2 else 0)

    def xf(self, p) -> tuple[int, int]:
        """A machine point in the planner's frame: the job's transform (identity unless fitted)."""
        c = self.cfg
        if c.scale_q16 == SCALE_ONE and not any(c.shift_um):
            return (p[0], p[1])
        return tuple((p[k] * c.scale_q16 + 32768 >> 16) + c.shift_um[k] for k in range(2))

    def xf_exact(self, p) -> tuple[float, float]:
        """The job's transform without rounding: for the exact path the contour is measured to."""
        c = self.cfg
        return tuple(p[k] * c.scale_q16 / SCALE_ONE + c.shift_um[k] for k in range(2))

    # ---- planner operations -----------------------------------------------------------------
    def _push(self, p, feed: int) -> None:
        end = self.xf(p)
        b = self.cfg.bounds_um
        if b is not None and not (b[0][0] <= end[0] <= b[1][0] and b[0][1] <= end[1] <= b[1][1]):
            self.alarm = 2
            raise GcodeAlarm(2, f"({end[0] / 1000:g}, {end[1] / 1000:g}) mm is outside the travel")
        self.plan.ops.append(("push", end[0], end[1], feed, self.tool, len(self.plan.ends)))
        self.plan.ends.append(end)
        self.plan.feed.append(feed)
        self.plan.tool.append(self.tool)
        self.last_tool = self.tool

    def _rest(self, ticks: int, tool: int) -> None:
        """A segment without steps (a dwell, a tool change) with a fixed tool word, once the
        planned motion is at rest."""
        self.plan.ops.append(("rest", ticks, tool))
        self.plan.dwell.append(ticks)
        self.tool = self.last_tool = tool

    # ---- the tool -----------------------------------------------------------------------------
    def idle_tool(self) -> int:
        """The tool word at rest: a laser is off (grbl's laser mode); a pen-like tool by its rule."""
        c = self.cfg
        if not c.pen_like:
            return 0
        rule = c.tool_rule
        if rule == "z":
            return self.cfg.pen_duty(self.mp[2] - self.wco(2) <= c.pen_z_um)
        if rule == "s":
            return self.cfg.pen_duty(self.spindle != 0 and self.s > 0)
        if rule == "m300":
            return self.cfg.pen_duty(self.pen)
        return self.cfg.pen_duty(False)

    def move_tool(self, rapid: bool, extrude: bool = False) -> int:
        """The tool word of a move: a laser by S (off in rapids and with M5; M4 scaled by speed) or
        by extrusion (Marlin's E rule); a pen-like tool by its rule."""
        c = self.cfg
        rule = c.tool_rule
        if rule == "e":
            return (255 if not c.pen_like else self.cfg.pen_duty(True)) if extrude else c.tool_off_duty
        if c.pen_like:
            return self.idle_tool()
        if rule != "s" or rapid or not self.spindle:
            return 0
        full = c.s_max * 1000
        t = min(self.s, full) * 255 // full
        return t | TOOL_SCALED if self.spindle == 4 else t

    # ---- lines --------------------------------------------------------------------------------
    def line(self, raw: bytes | str) -> str:
        """Run one line as the chip receives it; returns "ok", "error:N", "ALARM:N" or "$"
        (a $ line: the sender's, not the engine's). The detail of a refusal: self.last_error."""
        if isinstance(raw, str):
            raw = raw.encode("utf-8")
        self.line_no += 1
        self.last_error = ""
        rd = read_line(sendable(raw))
        try:
            if rd.kind == ERROR:
                raise GcodeLineError(rd.code)
            if rd.kind == DOLLAR:
                reply = "$"
            elif rd.kind == EMPTY:
                reply = "ok"
            else:
                if self.alarm:
                    raise GcodeLineError(9)
                blk = parse_block(rd.text, self.cfg.marlin, self.cfg.tool_rule == "m300", self.cfg.features)
                self.features_used |= blk.used
                self._block(blk)
                reply = "ok"
        except GcodeAlarm as exc:
            reply, self.last_error = f"ALARM:{exc.code}", str(exc)
        except GcodeLineError as exc:
            reply, self.last_error = f"error:{exc.code}", str(exc)
        self.plan.replies.append(reply)
        return reply

    def _note(self, name: str) -> None:
        self.notes[name] = self.notes.get(name, 0) + 1

    def _block(self, b: Block) -> None:  # noqa: C901  (one line, in grbl's order of execution)
        if b.noted_line:
            self._note(b.noted_line)
            return
        v = b.values
        for letter in "FPTS":
            g5_offset = letter == "P" and b.nonmodal is None and (self.motion if b.motion is None else b.motion) == 5
            if letter in v and v[letter].neg and not g5_offset:  # G5's P is an offset; G4's and G10's are not
                raise GcodeLineError(4, letter)
        if "T" in v and v["T"].ip > 255:
            raise GcodeLineError(38)
        inch = self.inch if b.inch is None else bool(b.inch)
        rel = self.relative if b.relative is None else bool(b.relative)
        plane = self.plane if b.plane is None else b.plane
        arc_abs = self.arc_abs if b.arc_abs is None else bool(b.arc_abs)
        inverse = self.inverse if b.inverse_time is None else bool(b.inverse_time)
        wcs = self.wcs if b.wcs is None else b.wcs
        motion = self.motion if b.motion is None else b.motion
        nm = b.nonmodal
        marlin = self.cfg.marlin
        used = set("NFTS")
        if b.m300 and "S" not in v:
            raise GcodeLineError(28, "M300 needs S")
        if "G64" in b.noted:
            used |= {"P", "Q"}
        axes = [a for a in "XYZ" if a in v]
        tlo = self.tlo
        if b.tlo == 1:  # G43.1 Z: the offset, not a move
            if "Z" not in v:
                raise GcodeLineError(37)
            tlo = v["Z"].to_um(inch)
            used.add("Z")
            axes.remove("Z")
        elif b.tlo == 0:
            tlo = 0
        elif b.tlo == 2:
            used.add("H")
        e_move = marlin and "E" in v and nm != 92
        axis_nm = nm in (10, 28, 30, 92)
        if (axes or e_move) and axis_nm and b.motion is not None and b.motion != 80:
            raise GcodeLineError(24)
        moving = bool(axes or e_move) and not axis_nm
        if moving and motion == 80:
            raise GcodeLineError(31)
        if b.motion in (2, 3) and not axis_nm and not axes:  # an arc written without its end
            raise GcodeLineError(32)
        # feed
        feed, inv_f = self.feed, 0
        if "F" in v:
            if inverse:
                inv_f = v["F"].to_um(False)
            else:
                feed = v["F"].to_um(inch)
            if (inv_f if inverse else feed) < (1 if inverse else MIN_FEED):
                raise GcodeLineError(22, "F below 1 mm/min" if not inverse else "F0 in G93")
        if inverse and moving and motion in (1, 2, 3, 5) and "F" not in v:
            raise GcodeLineError(22, "G93 needs F on every move")
        # targets (machine frame)
        if nm == 53 and moving and motion not in (0, 1):
            raise GcodeLineError(30)
        tgt = list(self.mp)
        for k, a in enumerate("XYZ"):
            if a not in axes:
                continue
            val = v[a].to_um(inch)
            if nm == 53:
                tgt[k] = val
            elif nm in (92, 10):
                tgt[k] = val  # read below, never a motion target
            elif rel:
                tgt[k] = self.mp[k] + val
            else:
                tgt[k] = val + self.wco(k, wcs, tlo)
            if abs(tgt[k]) > POS_LIMIT:
                raise GcodeLineError(33, f"{a} beyond {POS_LIMIT // 1000} mm")
            used.add(a)
        # E (Marlin): relative with M83 (or G91 without M82 since), absolute otherwise
        e_rel = self.e_rel if b.e_relative is None else bool(b.e_relative)
        if b.relative is not None and b.e_relative is None:
            e_rel = bool(b.relative)
        e_tgt, extrude = self.e, False
        if "E" in v:
            used.add("E")
            ev = v["E"].to_um(inch)
            if abs(ev) > POS_LIMIT:
                raise GcodeLineError(33, f"E beyond {POS_LIMIT // 1000} mm")
            if nm == 92 or not e_rel:
                e_tgt = ev
                extrude = nm != 92 and ev > self.e
            else:
                extrude = ev > 0  # relative E: only its sign matters
        # non-modal commands that check before anything changes
        dwell_ms = -1
        if nm == 4:
            if marlin and "S" in v and "P" not in v:
                dwell_ms = v["S"].to_um(False)
            elif "P" in v:
                p = v["P"].to_um(False)
                dwell_ms = (p + 500) // 1000 if marlin else p
            elif marlin:
                dwell_ms = 0  # Marlin: G4 alone waits for nothing
            else:
                raise GcodeLineError(28, "G4 needs P")
            used.add("P")
            dwell_ms = min(dwell_ms, DWELL_MS_MAX)
        if nm == 10:
            if "L" not in v or "P" not in v:
                raise GcodeLineError(28, "G10 needs L and P")
            used |= {"L", "P"}
            lv, pv = v["L"], v["P"]
            if lv.nd and lv.fr or lv.ip not in (2, 20):
                raise GcodeLineError(20, f"G10 L{lv.ip}")
            if pv.ip > 6 or (pv.nd and pv.fr):
                raise GcodeLineError(29, f"P{pv.ip}")
            if not axes:
                raise GcodeLineError(26, "G10")
        if nm == 92 and not axes and "E" not in v:
            raise GcodeLineError(26, "G92")
        # arcs and curves: centre, radius, chord ends (checked before anything changes)
        geom = None
        if moving and motion in (2, 3):
            geom = curves.arc(self, v, tgt, plane, inch, arc_abs, wcs, tlo, motion == 3, used)
        elif moving and motion == 5:
            if plane:
                raise GcodeLineError(20, "G5 outside G17")
            geom = curves.bezier(self, v, tgt, inch, used)
        unused = sorted(set(v) - used)
        if unused:
            raise GcodeLineError(36, " ".join(unused))
        # ---- commit: the modal state, then the action -------------------------------------
        if "F" in v and not inverse:
            self.feed = feed
        if "S" in v and not b.m300 and not (nm == 4 and marlin and "P" not in v):
            self.s = v["S"].to_um(False)
        if "T" in v:
            self.tool_no = v["T"].ip
        for name in b.noted:
            self._note(name)
        if b.spindle is not None:
            self.spindle = 0 if b.spindle == 5 else b.spindle
        if b.coolant is not None:
            self.coolant = 0 if b.coolant == 9 else self.coolant | (1 << (b.coolant - 7))
        if b.m300:
            self.pen = v["S"].to_um(False) <= self.cfg.m300_down_max * 1000
        self.plane, self.inch, self.relative, self.arc_abs, self.inverse = plane, inch, rel, arc_abs, inverse
        self.tlo, self.wcs, self.e_rel = tlo, wcs, e_rel
        if b.motion is not None:
            self.motion = b.motion
        self.last_wins += b.last_wins
        seg0 = len(self.plan.ends)
        if nm == 4:
            self._dwell(dwell_ms)
        elif nm == 10:
            p = v["P"].ip - 1 if v["P"].ip else self.wcs
            for k, a in enumerate("XYZ"):
                if a in axes:
                    val = v[a].to_um(inch)
                    self.coord[p][k] = val if v["L"].ip == 2 else \
                        self.mp[k] - self.g92[k] - (self.tlo if k == 2 else 0) - val
        elif nm == 92:
            for k, a in enumerate("XYZ"):
                if a in axes:
                    self.g92[k] = self.mp[k] - self.coord[self.wcs][k] - (self.tlo if k == 2 else 0) - v[a].to_um(inch)
        elif nm == 921:
            self.g92 = [0, 0, 0]
        elif nm in (281, 301):
            self.home[nm == 301] = list(self.mp)
        elif nm in (28, 30):
            self._home(nm == 30, axes, tgt)
        if moving:
            self._motion(motion, tgt, geom, extrude, inv_f)
        self.e = e_tgt
        if b.stop in (2, 30):  # program end as grbl: G1 G17 G90 G94 G54, M5 M9
            self.motion, self.plane, self.relative, self.inverse, self.wcs = 1, 0, False, False, 0
            self.spindle, self.coolant = 0, 0
        elif b.stop == 1:
            self._note("M1")
        # a tool word that turns a laser off (M5, S0, M2/M30) or moves the pen, and no block on this
        # line: the tool changes on the next tick, by a one-tick rest, if the last block left it
        # otherwise (a new power alone waits for the next cut)
        toolword = b.spindle is not None or "S" in v or "Z" in axes or b.stop in (2, 30) or b.m300
        if (toolword and len(self.plan.ends) == seg0 and self.last_tool != self.idle_tool()
                and (self.cfg.pen_like or self.move_tool(False) == 0)):
            self._rest(1, self.idle_tool())
        if b.wait or b.stop in (0, 2, 30):  # M400, M0 (resumed at once in a job), M2, M30
            self.plan.ops.append(("flush",))
            if b.stop == 0:
                self._note("M0")

    def _dwell(self, ms: int) -> None:
        t = ms // 1000 * self.cfg.tick_hz + ms % 1000 * self.cfg.tick_hz // 1000
        if t:
            self._rest(t, self.idle_tool())

    def _home(self, second: bool, axes: list[str], via: list[int]) -> None:
        """G28/G30: grbl: a rapid via the given axes, then the given axes (all if none) to the stored
        position; Marlin's G28 homes the given axes (all if none) without a via point."""
        stored = self.home[second]
        if axes and not self.cfg.marlin:
            self._line(via, self.cfg.rapid_um_min, True)
        dest = [stored[k] if ("XYZ"[k] in axes or not axes) else (via[k] if not self.cfg.marlin else self.mp[k])
                for k in range(3)]
        self._line(dest, self.cfg.rapid_um_min, True)

    def _line(self, tgt, feed: int, rapid: bool, extrude: bool = False) -> None:
        start = tuple(self.mp[:2])
        self.mp[2] = tgt[2]
        self.tool = self.move_tool(rapid, extrude)
        if (tgt[0], tgt[1]) != start:
            first = len(self.plan.ends)
            self._push(tgt, feed)
            self.mp[0], self.mp[1] = tgt[0], tgt[1]
            self.plan.moves.append(Move(self.line_no, "line", self.xf(start), self.xf(tgt), first, 1, rapid=rapid))
            self._count(rapid)

    def _count(self, rapid: bool) -> None:
        z = self.mp[2] - self.wco(2)
        self.z_seen = [min(self.z_seen[0], z), max(self.z_seen[1], z)] if self.z_seen else [z, z]
        if self.tool != self.cfg.tool_off_duty and not rapid:
            self.moves_on += 1
        else:
            self.moves_off += 1

    def _inverse_feed(self, length_um: int, inv_f: int) -> int:
        """G93: the move takes 1/F minutes: feed = length * F (F in thousandths per minute)."""
        return min(max(length_um * inv_f // 1000, MIN_FEED), (1 << 31) - 1)

    def _motion(self, motion: int, tgt: list[int], geom, extrude: bool, inv_f: int) -> None:
        rapid = motion == 0
        if motion in (0, 1):
            feed = self.cfg.rapid_um_min if rapid else self.feed
            if inv_f and not rapid:
                feed = self._inverse_feed(isqrt((tgt[0] - self.mp[0]) ** 2 + (tgt[1] - self.mp[1]) ** 2), inv_f)
            self._line(tgt, feed, rapid, extrude)
            return
        kind, pts3, extra = geom[:3]
        start = tuple(self.mp[:2])
        feed = self.feed
        if inv_f:
            feed = self._inverse_feed(chord_length([p[:2] for p in pts3], start), inv_f)
        first, k0 = len(self.plan.ends), len(self.plan.ops)
        if kind == "arc2d":
            self.mp[2] = tgt[2]  # a helix: Z (the tool's axis) at its end from the start
        self.tool = self.move_tool(False, extrude)
        for p in pts3:
            if kind != "arc2d":
                self.mp[2] = p[2]
                self.tool = self.move_tool(False, extrude)
            if (p[0], p[1]) != (self.mp[0], self.mp[1]):
                self._push(p, feed)
                self.mp[0], self.mp[1] = p[0], p[1]
        self.mp[2] = tgt[2]
        n = len(self.plan.ends) - first
        if n:
            self._count(False)
            if kind == "arc2d":
                c, r, ccw = extra
                s = self.cfg.scale_q16
                if self.cfg.arc_blocks and self.plane == 0:  # one planner block (planner_arc)
                    as_arc_op(self.plan.ops, k0, r * s // SCALE_ONE, self.cfg.acc_q16, length_q,
                              Planner(self.cfg).vertex)
                self.plan.moves.append(Move(self.line_no, "arc", self.xf(start), self.xf(tgt), first, n, self.xf(c),
                                  r * s // SCALE_ONE, ccw))
            else:
                self.plan.moves.append(Move(self.line_no, "poly", self.xf(start), self.xf(tgt), first, n,
                                  points=tuple(self.xf_exact(q) for q in extra)))
        self.bezier_c2 = geom[3] if motion == 5 else None

def run_lines(lines, cfg: MachineConfig) -> Interpreter:
    it = Interpreter(cfg)
    for raw in lines:
        it.line(raw)
    return it


__all__ = ["Interpreter", "run_lines", "describe"]
