"""Objectives over points (``m x d`` feature values -> ``m`` utilities) for continuous spaces.

Issue 13, item 5.  An objective is any function of an ``m x d`` array of points in the features'
units returning ``m`` utilities (higher is better); ``--objective PATH.py:NAME`` loads one from a
Python file (:func:`load_function`).  Two are built in, both over the space's box rescaled to
``[0, 1]^d``:

- ``hartmann6``: the Hartmann-6 function (Dixon & Szego 1978; the constants of Surjanovic &
  Bingham's library), negated so that higher is better, on the first six features (any further
  ones are ignored: an objective with a six-dimensional effective subspace); its maximum is
  ``3.32237`` at a known point.
- ``random-gp``: a draw from a GP with a squared-exponential kernel of lengthscale
  ``0.1 sqrt(d)`` (unit variance) by random Fourier features (Rahimi & Recht 2007):
  ``f(u) = sqrt(2 / M) sum_k w_k cos(omega_k . u + b_k)``, ``omega_k ~ N(0, I / l^2)``,
  ``b_k ~ U(0, 2 pi)``, ``w_k ~ N(0, 1)``, ``M = 1024``; seeded (``random-gp:SEED``).  Its
  maximum is estimated by :func:`estimate_optimum` (multistart L-BFGS-B).
"""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from gaitpref.limits import MAX_SEED
from gaitpref.space import FloatArray, Space

PointObjective = Callable[[FloatArray], FloatArray]

_H6_ALPHA = np.array([1.0, 1.2, 3.0, 3.2])
_H6_A = np.array(
    [
        [10, 3, 17, 3.5, 1.7, 8],
        [0.05, 10, 17, 0.1, 8, 14],
        [3, 3.5, 1.7, 10, 17, 8],
        [17, 8, 0.05, 10, 0.1, 14],
    ]
)
_H6_P = 1e-4 * np.array(
    [
        [1312, 1696, 5569, 124, 8283, 5886],
        [2329, 4135, 8307, 3736, 1004, 9991],
        [2348, 1451, 3522, 2883, 3047, 6650],
        [4047, 8828, 8732, 5743, 1091, 381],
    ]
)
#: The Hartmann-6 maximiser in ``[0, 1]^6`` and the (negated) maximum.
HARTMANN6_ARGMAX = (0.20169, 0.150011, 0.476874, 0.275332, 0.311652, 0.6573)
HARTMANN6_MAX = 3.32237


def hartmann6(u: FloatArray) -> FloatArray:
    """Negated Hartmann-6 at ``u`` (``m x 6``, in ``[0, 1]``): higher is better, max 3.32237."""
    diff = u[:, None, :] - _H6_P[None, :, :]
    inner = np.sum(_H6_A[None, :, :] * diff**2, axis=2)
    out: FloatArray = np.exp(-inner) @ _H6_ALPHA
    return out


@dataclass(frozen=True)
class RandomGP:
    """A GP sample by random Fourier features over ``[0, 1]^d`` (module docstring)."""

    omega: FloatArray  # M x d
    phase: FloatArray  # M
    weight: FloatArray  # M

    @classmethod
    def draw(cls, d: int, seed: int, lengthscale: float = 0.2, features: int = 1024) -> RandomGP:
        rng = np.random.default_rng(seed)
        omega = rng.standard_normal((features, d)) / lengthscale
        phase = rng.uniform(0.0, 2 * np.pi, features)
        weight = rng.standard_normal(features)
        return cls(omega, phase, weight)

    def __call__(self, u: FloatArray) -> FloatArray:
        scale = np.sqrt(2.0 / self.weight.size)
        out: FloatArray = scale * np.cos(u @ self.omega.T + self.phase) @ self.weight
        return out


def on_box(space: Space, fn: PointObjective, dims: int | None = None) -> PointObjective:
    """``fn`` of the first ``dims`` (default all) features rescaled to ``[0, 1]``."""
    lo = np.array([f.values[0] for f in space.features])
    span = np.array([f.span if f.span > 0 else 1.0 for f in space.features])
    k = space.ndim if dims is None else dims
    if space.ndim < k:
        raise ValueError(f"this objective needs at least {k} features; the space has {space.ndim}")

    def objective(points: FloatArray) -> FloatArray:
        u = (np.asarray(points, dtype=np.float64).reshape(-1, space.ndim) - lo) / span
        return fn(u[:, :k])

    return objective


BUILTINS = ("hartmann6", "random-gp")
_BUILTIN_SPECS = ("hartmann6", "random-gp[:SEED]")  # as the built-ins are written


def random_gp_lengthscale(d: int) -> float:
    """The built-in random GP's lengthscale in ``d`` dimensions, ``0.1 sqrt(d)``: as many bumps
    along the box's diagonal whatever ``d`` (0.24 in 6-D, 0.35 in 12-D)."""
    return 0.1 * float(np.sqrt(d))


def builtin(name: str, space: Space, seed: int = 0) -> PointObjective:
    """A built-in objective over ``space``: ``hartmann6`` or ``random-gp`` (seeded)."""
    if name == "hartmann6":
        return on_box(space, hartmann6, 6)
    if name == "random-gp":
        return on_box(space, RandomGP.draw(space.ndim, seed, random_gp_lengthscale(space.ndim)))
    raise ValueError(f"unknown built-in objective {name!r}; built in: {', '.join(BUILTINS)}")


def load_function(spec: str) -> PointObjective:
    """The function ``NAME`` of the Python file ``PATH`` given as ``PATH.py:NAME``."""
    path_text, sep, name = spec.rpartition(":")
    if not sep or not path_text.endswith(".py") or not name.isidentifier():
        # a mistyped built-in ('hartman6') or a .npy grid here said only 'expected PATH.py:NAME'
        grid = (
            " (a .npy file is one utility per grid point: `gaitpref simulate` takes it, a "
            "sweep over points does not)"
            if spec.endswith(".npy")
            else ""
        )
        raise ValueError(
            f"objective {spec!r}: expected PATH.py:NAME (a function in a Python file) or a "
            f"built-in: {', '.join(_BUILTIN_SPECS)}{grid}"
        )
    path = Path(path_text)
    if not path.is_file():
        raise ValueError(f"objective file {path_text!r} does not exist")
    module_spec = importlib.util.spec_from_file_location(f"_gaitpref_objective_{path.stem}", path)
    if module_spec is None or module_spec.loader is None:
        raise ValueError(f"objective file {path_text!r} cannot be imported")
    module = importlib.util.module_from_spec(module_spec)
    try:
        module_spec.loader.exec_module(module)
    except Exception as exc:  # the user's file: a syntax error, a failed import, ...
        raise ValueError(
            f"objective file {path_text!r} cannot be imported: {type(exc).__name__}: {exc}"
        ) from exc
    fn = getattr(module, name, None)
    if not callable(fn):
        raise ValueError(f"objective {spec!r}: {path_text} defines no function {name!r}")
    out: PointObjective = fn
    return out


def objective_from(spec: str, space: Space, seed: int = 0) -> PointObjective:
    """``PATH.py:NAME``, ``hartmann6``, ``random-gp`` or ``random-gp:SEED``, checked on two
    points of ``space`` (``m`` finite utilities for ``m`` points)."""
    head, sep, tail = spec.partition(":")
    if head in BUILTINS:
        if sep and head != "random-gp":  # hartmann6:5 ran hartmann6, the seed ignored
            raise ValueError(f"objective {spec!r}: {head} takes no seed; give {head!r}")
        digits = tail.lstrip("0")  # past MAX_SEED's 19 digits: refused before int() reads it
        if sep and not (
            tail.isascii() and tail.isdigit() and len(digits) <= 19 and int(digits or 0) <= MAX_SEED
        ):
            raise ValueError(
                f"objective {spec!r}: the seed after ':' must be an integer >= 0, "
                f"at most {MAX_SEED}"
            )
        fn = builtin(head, space, int(tail) if tail else seed)
    else:
        fn = checked_objective(load_function(spec), spec, space.ndim)
    lo = np.array([[f.values[0] for f in space.features]])
    probe = np.concatenate([lo, np.array([[f.values[-1] for f in space.features]])])
    values = np.asarray(fn(probe), dtype=np.float64)
    if values.shape != (2,) or not np.all(np.isfinite(values)):
        raise ValueError(
            f"objective {spec!r}: for a 2 x {space.ndim} array of points it must return 2 "
            f"finite utilities, got shape {values.shape}"
        )
    return fn


def checked_objective(fn: PointObjective, spec: str, ndim: int) -> PointObjective:
    """``fn`` (the user's function), checked at every call: an error it raises, or a result
    that is not ``m`` finite numbers for ``m`` points, is a ValueError naming ``spec`` (a
    traceback, or a NaN utility taken silently, before); so are booleans (numpy's "boolean
    subtract is not supported", naming nothing) and complex numbers (their imaginary parts
    dropped with a ComplexWarning).  The values pass through unchanged."""

    def objective(points: FloatArray) -> FloatArray:
        m = int(np.shape(points)[0])
        try:
            values = fn(points)
            dtype = np.asarray(values).dtype
            got = np.asarray(values, dtype=np.float64) if dtype.kind not in "bcV" else None
        except Exception as exc:
            raise ValueError(
                f"objective {spec!r} failed on {m} point(s): {type(exc).__name__}: {exc}"
            ) from exc
        if got is None:  # bool, complex, records: dropped or refused later, naming nothing
            raise ValueError(
                f"objective {spec!r}: for a {m} x {ndim} array of points it must return {m} "
                f"real utilities, got {dtype} values"
            )
        if got.shape != (m,) or not np.all(np.isfinite(got)):
            what = f"shape {got.shape}" if got.shape != (m,) else "values that are not finite"
            raise ValueError(
                f"objective {spec!r}: for a {m} x {ndim} array of points it must return {m} "
                f"finite utilities, got {what}"
            )
        return values

    return objective


def estimate_optimum(
    fn: PointObjective, space: Space, seed: int = 0, samples: int = 20000, starts: int = 10
) -> tuple[FloatArray, float]:
    """The best point and value found by random search then L-BFGS-B from the best ``starts``
    samples, in the box of ``space`` (continuous relaxation of discrete features)."""
    rng = np.random.default_rng(seed)
    lo = np.array([f.values[0] for f in space.features])
    hi = np.array([f.values[-1] for f in space.features])
    cand = lo + rng.uniform(size=(samples, space.ndim)) * (hi - lo)
    vals = np.asarray(fn(cand))
    best_x, best_v = cand[int(np.argmax(vals))], float(np.max(vals))
    for k in np.argsort(vals)[-starts:]:
        res = minimize(
            lambda x: -float(np.asarray(fn(x[None, :]))[0]),
            cand[k],
            method="L-BFGS-B",
            bounds=list(zip(lo, hi, strict=True)),
        )
        if -res.fun > best_v:
            best_x, best_v = np.asarray(res.x), float(-res.fun)
    return best_x, best_v


__all__ = [
    "BUILTINS",
    "HARTMANN6_ARGMAX",
    "HARTMANN6_MAX",
    "PointObjective",
    "RandomGP",
    "builtin",
    "checked_objective",
    "estimate_optimum",
    "hartmann6",
    "load_function",
    "objective_from",
    "on_box",
    "random_gp_lengthscale",
]
