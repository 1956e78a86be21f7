"""The keys of a DC-servo scenario's [servo], [servo.x], [servo.y], [servo.x.identified],
[servo.y.identified] and [controller] tables (issue 28), each with its unit and its range.

The tick must be one the Uno's Timer1 makes exactly (CTC at 16 MHz, prescaler 1, 8, 64, 256 or 1024,
OCR1A + 1 <= 65,536) and at least MIN_TICK_S: below 0.5 ms the tick's computation (two PID axes,
about 800 cycles each, plus the encoder interrupts at speed) no longer fits with room to spare.
"""

from __future__ import annotations

from nnik.machine.params import Param, within

F_CPU_HZ = 16_000_000  # the Uno's clock: Timer1 counts it through its prescaler
TIMER1_PRESCALERS = (8, 1, 64, 256, 1024)  # tried in this order: 8 first, as the firmware's design
TIMER1_TOP = 65_536  # OCR1A + 1 at most (16-bit)
MIN_TICK_S = 0.0005  # the documented floor (see the module docstring)
MAX_TICK_S = max(TIMER1_PRESCALERS) * TIMER1_TOP / F_CPU_HZ  # 4.194304 s, Timer1's longest period
MAX_SUBSTEPS = 1000
MIN_SUBSTEPS = 4
SUBSTEPS_PER_TAU_M = 20  # a substep is at most 1/20 of the mechanical time constant
MAX_SEED = 2**32 - 1
CONTROLLER_KINDS = ("auto", "pid", "pdff", "ccc", "nn_axes", "nn_vector")


def timer1_setting(tick_s: float) -> tuple[int, int] | None:
    """(prescaler, OCR1A) of the Timer1 CTC period that is exactly tick_s at 16 MHz: prescaler 8 when
    it can (5 ms = 9,999, 1 ms = 1,999), else 1, 64, 256, 1024; None when none makes it exactly."""
    for pre in TIMER1_PRESCALERS:
        n = round(tick_s * F_CPU_HZ / pre)
        if 1 <= n <= TIMER1_TOP and abs(n * pre - tick_s * F_CPU_HZ) <= 1e-6 * pre:
            return pre, n - 1
    return None


def tick_problem(v: float) -> str | None:
    if not MIN_TICK_S <= v <= MAX_TICK_S:
        return f"must be in [{MIN_TICK_S:g}, {MAX_TICK_S:g}] s (the floor is nnik's: the tick's work must fit), got {v:g}"
    if timer1_setting(v) is None:
        return (f"{v:g} s is not a period the Uno's Timer1 makes exactly (16 MHz / prescaler "
                f"{', '.join(map(str, TIMER1_PRESCALERS))} / (OCR1A + 1)); e.g. 0.005 or 0.001")
    return None


SERVO = {
    "tick_s": Param("float", default=0.005, check=tick_problem,
                    doc="the control tick (Timer1 CTC), s; seed 001: 5 ms"),
    "supply_v": Param("float", default=12.0, check=within(0.0, 60.0, open_lo=True, unit=" V"),
                      doc="the H-bridge's supply: full duty puts this across the armature"),
    "pwm_bits": Param("int", default=8, choices=(8,), doc="PWM resolution: the Uno's Timer2 is 8-bit (duty_max 255)"),
    "encoder": Param("str", default="quadrature", choices=("quadrature", "counter8"),
                     doc="quadrature: 4x edges counted on interrupts; counter8: the seed's 8-bit counters, read each tick"),
    "substeps": Param("int", default=40, check=within(MIN_SUBSTEPS, MAX_SUBSTEPS),
                      doc="plant integration steps per tick (friction, backlash and encoder edges between them)"),
    "x": Param("table", required=True, doc="the X motor"),
    "y": Param("table", required=True, doc="the Y motor"),
}

AXIS = {  # all at the MOTOR shaft except backlash_um (at the table) and gear_ratio
    "ra_ohm": Param("float", required=True, check=within(0.0, 1000.0, open_lo=True, unit=" ohm"),
                    doc="armature resistance"),
    "la_h": Param("float", required=True, check=within(0.0, 10.0, open_lo=True, unit=" H"),
                  doc="armature inductance"),
    "ke_v_s_rad": Param("float", required=True, check=within(0.0, 10.0, open_lo=True, unit=" V s/rad"),
                        doc="back-EMF constant at the motor shaft (= torque constant, N m/A)"),
    "j_kg_m2": Param("float", required=True, check=within(0.0, 1.0, open_lo=True, unit=" kg m^2"),
                     doc="inertia at the motor shaft: rotor, gearbox, and screw and carriage reflected"),
    "viscous_n_m_s_rad": Param("float", default=0.0, check=within(0.0, 1.0, unit=" N m s/rad"),
                               doc="viscous friction at the motor shaft"),
    "coulomb_n_m": Param("float", default=0.0, check=within(0.0, 100.0, unit=" N m"),
                         doc="Coulomb (sliding) friction at the motor shaft"),
    "stiction_n_m": Param("float", default=0.0, check=within(0.0, 100.0, unit=" N m"),
                          doc="break-away torque at the motor shaft, >= coulomb_n_m; 0: off"),
    "backlash_um": Param("float", default=0.0, check=within(0.0, 10_000.0, unit=" um"),
                         doc="play between the gearbox and the table, in table travel; 0: off"),
    "gear_ratio": Param("float", default=1.0, check=within(0.0, 10_000.0, open_lo=True),
                        doc="motor turns per screw turn"),
    "identified": Param("table", default=None, doc="an identified speed model (nnik identify writes it)"),
}

IDENTIFIED = {
    "k_counts_s_v": Param("float", required=True, check=within(0.0, 1e9, open_lo=True, unit=" counts/s/V"),
                          doc="steady speed per volt"),
    "tau_s": Param("float", required=True, check=within(0.0, 1e3, open_lo=True, unit=" s"),
                   doc="speed time constant"),
}

CONTROLLER = {
    "kind": Param("str", default="auto", choices=CONTROLLER_KINDS,
                  doc="the controller to ship; auto: the lowest RMS contour error on the reference job on the "
                       "identified plant"),
    "tune_trials": Param("int", default=60, check=within(1, 10_000), doc="tuning trials per controller"),
    "seed": Param("int", default=0, check=within(0, MAX_SEED), doc="the tuner's seed"),
    "max_overshoot_um": Param("float", default=25.0, check=within(0.0, 1e6, unit=" um"),
                              doc="largest overshoot a tuned controller may show on the reference steps"),
    "max_saturated_fraction": Param("float", default=0.05, check=within(0.0, 1.0, unit=""),
                                    doc="share of the reference job's ticks at which a duty may sit at +-duty_max"),
}

