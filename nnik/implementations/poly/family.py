"""The ``poly`` family: one polynomial per output in the normalised inputs, evaluated by Horner's
scheme in int16 values with int32 products.

* Normalisation and symmetry: :mod:`nnik.implementations.poly.fit` (the symmetry is detected
  from the problem's own truth and drops monomials; measured data get none).
* Fit: minimax (``scipy.optimize.linprog``, L-inf on the fit samples) or least squares.
* Integer program, exponents by range analysis, interval proof, numpy model:
  :mod:`nnik.implementations.poly.int_model`; its C: :mod:`nnik.implementations.poly.c` and
  ``codegen/templates/poly_ik.c.j2``.

Knobs: ``degree`` (total), optional ``degree_x``/``degree_y`` (per axis), ``fit``
(minimax | lsq | best, or one per output; best = the one whose integer model errs least per output
on a random probe set, never the check grid), ``trim`` (a constant multiplier may give up that
many bits so that its step shifts by exactly 16), ``rounding`` (round half up in each step, or
floor), ``coef_bits`` (16: int16 coefficients added after each shift; 32: int32
coefficients added to the product before it, one rounding per step), ``split`` (bool or one per
output: the last factor of an odd output is a constant plus a finer residual: one more product,
more bits),
``lsb`` (the bits the input shift drops, 0 .. 2^k - 1, enter each output linearly with a fitted
slope: one more product per input, and the int16 input no longer limits the accuracy), ``guard``
(extra headroom bits; when given, the range analysis must prove it as is), ``width`` (16: int16
values as above; 32: the wide path, int32 values and 64-bit products, unshifted int32 inputs:
:mod:`nnik.implementations.poly.wide`; no split, no dropped-bits correction).

A final product by a constant whose int16 rounding would cost more than ``CONST_TOL`` output
units gets a second product with the constant's remainder (affine belt machines need it).
"""

from __future__ import annotations

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.base import Implementation, IntRun
from nnik.implementations.problem import Problem
from nnik.implementations.poly import fit as poly_fit

from nnik.implementations.poly import int_model as poly_int
DEFAULTS = {"degree": 5, "fit": "best", "coef_bits": 16, "split": False, "trim": 4, "rounding": True, "lsb": False,
            "width": 16}
WIDE_FROM = 3  # the wide (32-bit) rungs start at this degree
MAX_DEGREE = 9  # what fit() accepts; the ladder stops earlier once a degree no longer improves the fit
CONST_TOL = 1e-3  # output units: a final constant multiplier rounded worse than this gets a low part
NEGLIGIBLE = 1e-6  # output units: a term smaller than this over the domain is dropped
KNOBS = set(DEFAULTS) | {"degree_x", "degree_y", "guard"}
RANGE_GRID = 257


FITS = ("minimax", "lsq", "best")
PROBE = 200_000


def _probe(p: Problem) -> tuple[np.ndarray, np.ndarray]:
    """Points to choose between fits on: random in-domain inputs (analytic) or the fit rows."""
    if "poly_probe" not in p.cache:
        if p.analytic:
            pts = np.random.default_rng(11).integers(p.lo, p.hi + 1, (PROBE, 2))
            p.cache["poly_probe"] = (pts, p.truth(pts))
        else:
            x, q = p.fit_samples()
            p.cache["poly_probe"] = (np.rint(x).astype(np.int64), q)
    return p.cache["poly_probe"]


def _symmetry(p: Problem) -> list:
    if "poly_symmetry" not in p.cache:
        p.cache["poly_symmetry"] = poly_fit.detect_symmetry(p)
    return p.cache["poly_symmetry"]


class PolyImpl(Implementation):
    family = "poly"
    doc = "bivariate polynomial per output, symmetric terms only, Horner in int16 on the hardware multiplier"
    grows_by = "degree"
    grows_within = "width"  # the degree grows, and stalls, separately in 16 and in 32 bits

    @classmethod
    def ladder(cls, problem: Problem) -> list[dict]:
        """Total degree 1..MAX_DEGREE (a degree whose symmetric term sets equal the previous one's is
        skipped; selection.fit_ladder stops growing the degree once the fit stops improving, see
        ``grows_by``); per degree, without and with the dropped-input-bits correction (when an input
        shift drops bits); no split, the split of each output, of both; from degree 3 each also
        with floor steps (3 AVR cycles a step cheaper). The fit is chosen per output ("best").
        Then the wide rungs (``width`` 32), degree WIDE_FROM and up: selection reaches them only
        when the 16-bit ladder has not met the target (they cost several times the cycles)."""
        sym = _symmetry(problem)
        maps = poly_fit.axis_maps(problem)
        lsbs = (False, True) if any(m.k > 0 for m in maps) else (False,)
        splits = [False, [True, False], [False, True], True]
        out, seen = [], set()
        for d in range(1, MAX_DEGREE + 1):
            terms = tuple(tuple(poly_fit.monomials(s, d)) for s in sym)
            if terms in seen:
                continue
            seen.add(terms)
            for lsb in lsbs:
                for sp in splits:
                    for r in ((True,) if d < 3 else (True, False)):
                        out.append({"degree": d, "fit": "best", "coef_bits": 16, "split": sp, "trim": 4,
                                    "rounding": r, "lsb": lsb})
        wide = sorted({cfg["degree"] for cfg in out if cfg["degree"] >= WIDE_FROM})
        return out + [{"degree": d, "fit": "best", "coef_bits": 32, "split": False, "trim": 4, "rounding": True,
                       "lsb": False, "width": 32} for d in wide]

    @classmethod
    def fit(cls, problem: Problem, config: dict) -> "PolyImpl":
        unknown = set(config) - KNOBS
        if unknown:
            raise NnikError(f"poly: unknown knob(s) {', '.join(sorted(unknown))}")
        cfg = {**DEFAULTS, **config}
        deg = cfg["degree"]
        if not isinstance(deg, int) or not 1 <= deg <= MAX_DEGREE:
            raise NnikError(f"poly: degree must be an integer in 1..{MAX_DEGREE}, got {deg!r}")
        if cfg["coef_bits"] not in (16, 32):
            raise NnikError(f"poly: coef_bits must be 16 or 32, got {cfg['coef_bits']!r}")
        if cfg["width"] not in (16, 32):
            raise NnikError(f"poly: width must be 16 or 32, got {cfg['width']!r}")
        if cfg["width"] == 32 and (cfg["split"] or cfg["lsb"] or cfg["coef_bits"] != 32):
            raise NnikError("poly: width 32 takes coef_bits 32, no split and no lsb (its inputs keep every bit)")
        split = cfg["split"]
        if not (isinstance(split, bool) or (isinstance(split, list) and len(split) == 2
                                            and all(isinstance(v, bool) for v in split))):
            raise NnikError(f"poly: split must be true, false or a list of two booleans, got {split!r}")
        how = cfg["fit"]
        hows = how if isinstance(how, list) else [how, how]
        if len(hows) != 2 or any(h not in FITS for h in hows):
            raise NnikError(f"poly: fit must be one of {', '.join(FITS)} or a list of two, got {how!r}")
        self = cls(problem, cfg)
        self.maps = poly_fit.axis_maps(problem)
        self.sym = _symmetry(problem)
        if "best" in hows:
            # per output, the fit whose integer model errs least on a probe set (not the check grid)
            trial = {h: cls.fit(problem, {**cfg, "fit": h}) for h in ("minimax", "lsq")}
            pts, truth = _probe(problem)
            err = {h: np.abs(im.run(pts).pre - truth).max(0) for h, im in trial.items()}
            hows = [min(("minimax", "lsq"), key=lambda h: err[h][o]) if hows[o] == "best" else hows[o]
                    for o in range(2)]
        self.fits = hows
        t, q, delta = poly_fit.fit_data(problem)
        wide = cfg["width"] == 32
        if wide:  # unshifted inputs: the fit is in the exact t
            t = t + delta
        self.coefs, self.lsb = [], []
        for o in range(2):
            terms = poly_fit.monomials(self.sym[o], deg, cfg.get("degree_x"), cfg.get("degree_y"))
            # the dropped input bits enter linearly, for each axis the output depends on
            axes = [a for a in range(2) if cfg["lsb"] and self.maps[a].k > 0 and
                    not (self.sym[o].indep_x if a == 0 else self.sym[o].indep_y)]
            key = ("poly_coefs", o, tuple(terms), hows[o], tuple(axes)) + (("exact t",) if wide else ())
            if key not in problem.cache:
                problem.cache[key] = poly_fit.fit_poly(t, q[:, o], terms, hows[o],
                                                       delta[:, axes] if axes else None)
            c = problem.cache[key]
            tmax = np.abs(t).max(0)
            keep = {ij: float(v) for ij, v in zip(terms, c[1:1 + len(terms)])
                    if abs(v) * tmax[0] ** ij[0] * tmax[1] ** ij[1] > NEGLIGIBLE}
            self.coefs.append((float(c[0]), keep))
            self.lsb.append({("rx", "ry")[a]: float(v) for a, v in zip(axes, c[1 + len(terms):])})
        self._build()
        return self

    # ---- integer program ---------------------------------------------------------------------------
    def _urange(self) -> list[tuple[int, int]]:
        p = self.problem
        return [(int(self.maps[a].u(np.array([p.lo[a]]))[0]), int(self.maps[a].u(np.array([p.hi[a]]))[0]))
                for a in range(2)]

    def _build(self) -> None:
        if self.config["width"] == 32:
            from nnik.implementations.poly import wide

            wide.build(self, RANGE_GRID)
            return
        ur = self._urange()
        gx = np.unique(np.rint(np.linspace(*ur[0], RANGE_GRID)))
        gy = np.unique(np.rint(np.linspace(*ur[1], RANGE_GRID)))
        tx, ty = (g.ravel() / 32768.0 for g in np.meshgrid(gx, gy, indexing="xy"))
        env = {"u": tx, "v": ty}
        poly_int.Node._n = 0  # deterministic names, hence a deterministic C text
        u, v = poly_int.Node("in", name="u"), poly_int.Node("in", name="v")
        shared = {"u": u, "v": v, "u2": poly_int.Node("mac", u, u, name="u2"),
                  "v2": poly_int.Node("mac", v, v, name="v2"), "uv": poly_int.Node("mac", u, v, name="uv")}
        split = self.config["split"]
        split = split if isinstance(split, list) else [split, split]
        self.plans = [poly_int.plan_output(coefs, c00, shared, sp, env)
                      for (c00, coefs), sp in zip(self.coefs, split)]
        for plan, lsb in zip(self.plans, self.lsb):
            for nm, c in lsb.items():
                plan.terms.append((poly_int.Node("in", name=nm), c))
                plan.shape += f" + {nm}"
        for a, nm in enumerate(("rx", "ry")):
            k = max(self.maps[a].k, 0)
            env[nm] = np.full(len(tx), ((1 << k) - 1) / 2.0 ** (15 + k))
            env[f"e_{nm}"] = 15 + k
        for plan in self.plans:
            plan.terms = poly_int.split_constants(plan.terms, env, CONST_TOL)
        self.prog = poly_int.build_proven(self.plans, env, self.config, ur,
                                          tuple((1 << max(m.k, 0)) - 1 for m in self.maps), self.describe)

    def run(self, in_units: np.ndarray) -> IntRun:
        p = self.problem
        c, flags = p.clamp(in_units)
        if self.config["width"] == 32:
            from nnik.implementations.poly import wide

            num = wide.run_num(self, c)
        else:
            num = poly_int.evaluate(self.prog, self.maps[0].u(c[:, 0]), self.maps[1].u(c[:, 1]),
                                    self.maps[0].r(c[:, 0]), self.maps[1].r(c[:, 1]))
        pre = np.empty(num.shape, dtype=np.float64)
        out = np.empty(num.shape, dtype=np.int64)
        for k, o in enumerate(self.prog.outs):
            pre[:, k] = num[:, k] / 2.0**o.s + o.offset
            out[:, k] = p.finish(num[:, k], o.s, o.offset)
        return IntRun(pre=pre, out=out, flags=flags)

    # ---- description -------------------------------------------------------------------------------
    def symmetry_text(self) -> str:
        return "; ".join(f"{name}: {s.label()}" for name, s in zip(self.problem.outputs, self.sym))

    def describe(self) -> str:
        c = self.config
        deg = f"degree {c['degree']}"
        if "degree_x" in c or "degree_y" in c:
            deg += f" (x <= {c.get('degree_x', c['degree'])}, y <= {c.get('degree_y', c['degree'])})"
        n = sum(len(k) + 1 for _, k in self.coefs) if hasattr(self, "coefs") else 0
        sp = c["split"]
        sp_text = (", split" if sp is True else "") if not isinstance(sp, list) else \
            (", split " + "+".join(n for n, v in zip(self.problem.outputs, sp) if v) if any(sp) else "")
        fits = getattr(self, "fits", None) or [c["fit"]] * 2
        fit_text = fits[0] if fits[0] == fits[1] else "/".join(fits)
        wide = ", 32-bit Horner (int32 values, 64-bit products)" if c.get("width") == 32 else ""
        return (f"poly {deg}, {fit_text}, {c['coef_bits']}-bit coefficients{wide}{sp_text}, "
                f"{n} coefficients; {self.symmetry_text() if hasattr(self, 'sym') else ''}")

    @property
    def n_coefficients(self) -> int:
        return sum(len(k) + 1 for _, k in self.coefs)

    def model_bytes(self) -> int:
        """Constants in the code: int16 coefficients (int32 in 32-bit mode), int32 sums."""
        if self.config["width"] == 32:
            from nnik.implementations.poly import wide

            return wide.model_bytes(self)
        cb = 2 if self.config["coef_bits"] == 16 else 4
        n = sum(cb if isinstance(st.L, int) or (st.K and self.config["coef_bits"] == 32) else 0
                for st in self.prog.steps)
        n += sum(2 for st in self.prog.steps if isinstance(st.b, int))
        n += sum(4 + sum(2 for _, b, _ in o.terms if isinstance(b, int)) for o in self.prog.outs)
        return n

    # ---- C and cost ----------------------------------------------------------------------------------
    def render_source(self) -> str:
        from nnik.implementations.poly import avr as poly_avr
        from nnik.implementations.poly import c as poly_c
        from nnik.implementations.c_common import comment_safe, environment
        from nnik.implementations.poly.p18 import p18_body

        p = self.problem
        if self.config["width"] == 32:
            from nnik.implementations.poly import wide

            return wide.render(self)
        used = poly_c.lsb_used(self.prog)
        avr_asm = poly_avr.body(self.prog, p.code_range, p.name)
        name = p.name
        shift_text = [f">> {m.k}" if m.k > 0 else (f"<< {-m.k}" if m.k < 0 else "") for m in self.maps]
        outs = [{"label": comment_safe(p.outputs[k]), "shape": plan.shape, "offset": o.offset, "s": o.s,
                 "nterms": len(self.coefs[k][1]) + 1}
                for k, (plan, o) in enumerate(zip(self.plans, self.prog.outs))]
        return environment().get_template("poly_ik.c.j2").render(
            name=name, NAME=name.upper(), scenario=comment_safe(p.scn.name), describe=comment_safe(self.describe()),
            maps=self.maps, shift_text=shift_text, symmetry=comment_safe(self.symmetry_text()), outs=outs,
            symmetry_of="the exact IK" if p.reference is None else "the reference model",
            values=poly_c.values(self.prog), input_lines=poly_c.input_lines(self.maps, p.lo, p.hi, used=used),
            c_steps=poly_c.portable_steps(self.prog),
            c_out=poly_c.output_lines(self.prog, p.code_range, lambda a, b: f"(int32_t){a} * {b}"),
            avr_steps=poly_c.avr_steps(self.prog, name),
            avr_in=poly_c.input_lines(self.maps, p.lo, p.hi, name=name if avr_asm else None, used=used),
            avr_out=poly_c.output_lines(self.prog, p.code_range, lambda a, b: f"{name}_mul({a}, {b})", name=name),
            avr_asm=avr_asm, lsb_used=used, p18_body=p18_body(self))

    def estimate(self, target: str) -> dict:
        from nnik.implementations.poly.cost import estimate

        if self.config["width"] == 32:
            from nnik.implementations.poly import wide

            return wide.estimate(self, target)
        return estimate(self, target)


IMPLEMENTATION = PolyImpl
