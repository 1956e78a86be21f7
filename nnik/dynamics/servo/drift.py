"""Plants off the identified one, for the honest comparison (issue 29): one whose parameters drift
during the job, and one that differs from the nominal from the start.

Drift (`DriftPlant`): over the job the load grows by 50 %, friction doubles and the supply sags by
20 % (`JOB_DRIFT`), each factor ramped linearly from 1 in `pieces` equal pieces of the job's ticks:
piece p (0 .. pieces - 1) holds the parameters at the fraction p / (pieces - 1) of the drift, so
the first piece is the nominal plant and the last the fully drifted one. Within a piece the plant
is exactly Plant's (its matrices rebuilt once per piece by AxisMatrices.build, the exact
discretisation of that piece's parameters); at a piece's start the state (current, speed, angle,
stuck or sliding) carries over. Ticks past `ticks` stay in the last piece.

What each factor changes, per axis:
- load +50 %: the inertia at the motor J x 1.5 (the reflected load is a small share of J on the
  shipped table, so this stands for a much heavier carriage; the load's extra friction is the
  friction factor's part);
- friction x 2: Coulomb, viscous and stiction (break-away) torques all x 2;
- supply -20 %: supply_v x 0.8: the same duty gives 20 % fewer volts (the controller is not told).

Differing (`differing(cfg)`): the plant differs from the identified one all along: J x 1.4,
Ra x 1.2 (La kept, so La/Ra shrinks), Coulomb, viscous and stiction x 1.5, Ke (= Kt) x 0.9: a
slower (free speed about -12 %), weaker (stall torque -25 %), more sluggish axis (`DIFFERING`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from nnik.dynamics.servo.config import MotorAxis, ServoConfig
from nnik.dynamics.servo.motor import AxisMatrices
from nnik.dynamics.servo.plant import Plant
from nnik.dynamics.servo.servo_error import ServoError


@dataclass(frozen=True)
class Drift:
    """Factors on the nominal parameters at the drift's end (1 = unchanged)."""

    inertia: float = 1.0  # J
    friction: float = 1.0  # Coulomb, viscous and stiction
    supply: float = 1.0  # supply_v
    ke: float = 1.0  # Ke = Kt
    ra: float = 1.0  # Ra (La kept)

    def at(self, frac: float) -> "Drift":
        """The factors a fraction `frac` (0 .. 1) of the way from 1 to these."""
        f = float(frac)
        return Drift(*(1.0 + f * (v - 1.0) for v in (self.inertia, self.friction, self.supply, self.ke, self.ra)))

    def apply_axis(self, ax: MotorAxis) -> MotorAxis:
        return replace(ax, j_kg_m2=ax.j_kg_m2 * self.inertia, ra_ohm=ax.ra_ohm * self.ra,
                       ke_v_s_rad=ax.ke_v_s_rad * self.ke,
                       coulomb_n_m=ax.coulomb_n_m * self.friction, stiction_n_m=ax.stiction_n_m * self.friction,
                       viscous_n_m_s_rad=ax.viscous_n_m_s_rad * self.friction)

    def apply(self, cfg: ServoConfig) -> ServoConfig:
        """cfg with these factors on both axes and the supply."""
        return replace(cfg, axes=tuple(self.apply_axis(ax) for ax in cfg.axes), supply_v=cfg.supply_v * self.supply)


NOMINAL = Drift()
JOB_DRIFT = Drift(inertia=1.5, friction=2.0, supply=0.8)
DIFFERING = Drift(inertia=1.4, friction=1.5, ke=0.9, ra=1.2)
PIECES = 10


def differing(cfg: ServoConfig) -> ServoConfig:
    """The plant that differs from the identified one (DIFFERING's factors, from the start)."""
    return DIFFERING.apply(cfg)


class DriftPlant(Plant):
    """A Plant whose parameters follow `drift` over `ticks` ticks in `pieces` pieces (see above);
    the same step() / counts / raw8 / table_um as Plant. `cfg` (the plant's parameters now) changes
    at each piece's first tick."""

    def __init__(self, cfg: ServoConfig, ticks: int, drift: Drift = JOB_DRIFT, pieces: int = PIECES,
                 start_counts: tuple[int, int] = (0, 0)):
        if not (isinstance(pieces, int) and pieces >= 2):
            raise ServoError(f"a drift needs at least 2 pieces (nominal first, drifted last), not {pieces!r}")
        if not (isinstance(ticks, int) and ticks >= 1):
            raise ServoError(f"a drift needs the job's length in ticks (>= 1), not {ticks!r}")
        super().__init__(cfg, start_counts)
        self.nominal = cfg
        self.drift, self.ticks, self.pieces = drift, ticks, pieces
        self.tick_index = 0
        self._piece = 0
        self._mats = {0: self._m}

    def piece(self, tick: int) -> int:
        """The piece that holds tick `tick` (the last one past the job's end)."""
        return min(self.pieces - 1, tick * self.pieces // self.ticks)

    def fraction(self, tick: int) -> float:
        """The share of the drift in force at tick `tick`."""
        return self.piece(tick) / (self.pieces - 1)

    def step(self, duty: tuple[int, int]):
        p = self.piece(self.tick_index)
        if p != self._piece:
            self.cfg = self.drift.at(p / (self.pieces - 1)).apply(self.nominal)
            if p not in self._mats:
                h = self.cfg.tick_s / self.cfg.substeps
                self._mats[p] = [AxisMatrices.build(ax, h, self.cfg.substeps) for ax in self.cfg.axes]
            self._m, self._piece = self._mats[p], p
        self.tick_index += 1
        return super().step(duty)
