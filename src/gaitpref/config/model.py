"""The ``[model]`` and ``[model.prior]`` tables: the kernel, the noise and the learning settings.

Besides each key's own bounds (``schema.py``), the scales are checked together: the ratio of
signal to noise ``signal_variance * max(1, coactive_weight)**2 / noise**2`` (a suggestion enters
with noise ``noise / coactive_weight``) is at most
:data:`~gaitpref.config.schema.MAX_SIGNAL_TO_NOISE`,
because beyond it the probit likelihood is nearly deterministic and the Laplace fit's Hessian
``I + H^T H`` (``model/laplace.py``) cannot be factorised in floating point; and the jitter, a
numerical nugget on the prior's diagonal, is at most the signal variance (issue 15, item 3).
"""

from __future__ import annotations

from typing import Any, cast

from gaitpref.config.schema import (
    DEFAULTS_VERSION,
    MAX_SIGNAL_TO_NOISE,
    MODEL,
    PRIOR,
    Key,
    check_table,
    defaults_for,
)
from gaitpref.config.specs import SCALE, LogNormalPair, fail
from gaitpref.loop.learning import FitMode, HyperMode, Learning, ShareMode, TiesMode, WarmFirst
from gaitpref.model.engines import resolve_sampler
from gaitpref.model.hyperfit import HyperPrior, LogNormal, default_prior
from gaitpref.model.kernels import SquaredExponential
from gaitpref.space import Space

#: ``[model] jitter`` left out (defaults 0.7 on): this fraction of ``signal_variance``.  Without a
#: nugget the prior covariance of many close visited points (the line path's clusters near a
#: boundary) is not positive definite in floating point, and the session stops mid-run.
RELATIVE_JITTER = 1e-6


def check_model(
    raw: object, defaults: str = DEFAULTS_VERSION
) -> tuple[dict[str, Any], frozenset[str]]:
    """``[model]`` with every key checked and the defaults of version ``defaults`` filled in,
    and the keys that defaulted (``model.share``: ``"map"`` before 0.6; ``model.jitter``:
    :data:`RELATIVE_JITTER` times ``signal_variance`` since 0.7, 0 before)."""
    model, defaulted = check_table(raw, "model", MODEL, defaults_for(defaults, "model"))
    if model["jitter"] is None:  # the default since 0.7: a nugget relative to the signal
        model["jitter"] = RELATIVE_JITTER * model["signal_variance"]
    return model, frozenset(f"model.{k}" for k in defaulted)


def check_scales(model: dict[str, Any], coactive_weight: float) -> None:
    """The signal-to-noise and jitter bounds (module docstring)."""
    variance, noise, jitter = model["signal_variance"], model["noise"], model["jitter"]
    ratio = variance * max(1.0, coactive_weight) ** 2 / noise**2
    if ratio > MAX_SIGNAL_TO_NOISE:
        weight = f" * coactive_weight**2 ({coactive_weight:g}**2)" if coactive_weight > 1 else ""
        fail(
            "model",
            "noise",
            f"signal_variance{weight} / noise**2 is {ratio:.3g}, more than "
            f"{MAX_SIGNAL_TO_NOISE:g}: preferences this nearly deterministic cannot be fitted "
            "(the Laplace fit's Hessian cannot be factorised); use a larger noise or a smaller "
            "signal_variance",
        )
    if jitter > variance:
        fail(
            "model",
            "jitter",
            f"must be at most signal_variance ({variance:g}), got {jitter:g}: the jitter is a "
            "small nugget that keeps the prior positive definite, not a second signal",
        )


def make_kernel(model: dict[str, Any], space: Space) -> SquaredExponential:
    value = model["lengthscale"]
    if isinstance(value, dict):
        keys = {name: Key(SCALE) for name in space.names}
        scales, _ = check_table(value, "model.lengthscale", keys)
        lengthscale = tuple(scales[n] for n in space.names)
    else:
        lengthscale = (value,) * space.ndim
    return SquaredExponential(lengthscale, model["signal_variance"], model["jitter"])


def check_sampler(model: dict[str, Any], size: int) -> str:
    try:
        resolve_sampler(model["sampler"], size)
    except ValueError as exc:
        fail("model", "sampler", str(exc))
    return str(model["sampler"])


def _log_normal(pair: tuple[float, float], table: str, key: str) -> LogNormal:
    try:
        return LogNormal(*pair)
    except ValueError as exc:
        fail(table, key, str(exc))


def _band(model: dict[str, Any]) -> float | None:
    ties, fit, raw_band = model["ties"], model["fit"], model["tie_band"]
    if ties == "drop":
        if raw_band is not None:
            fail("model", "tie_band", 'only used with ties = "model"')
        return None
    if raw_band is None:
        if fit != "evidence":
            fail("model", "tie_band", 'ties = "model" with fit = "fixed" needs a number')
        return None
    if raw_band == "fit":
        if fit != "evidence":
            fail("model", "tie_band", '"fit" needs fit = "evidence"')
        return None
    return float(raw_band)


def make_learning(model: dict[str, Any], space: Space) -> Learning:
    """Ties, the tie band, the fit mode, the refit interval and the hyperparameter prior."""
    band = _band(model)
    learns_band = model["ties"] == "model" and band is None
    for f in space.features:  # the default lengthscale prior's median is a quarter of the range
        if f.span > 0 and not 0.25 * f.span > 0:
            fail(f"space.{f.name}", None, f"range {f.span!r} is too small to give a lengthscale")
    prior = default_prior(space, model["signal_variance"], model["noise"], fit_band=learns_band)
    raw, _ = check_table(model["prior"], "model.prior", PRIOR)
    scales = list(prior.lengthscale)
    if raw["lengthscale"] is not None:
        keys = {name: Key(LogNormalPair(), None) for name in space.names}
        table, _ = check_table(raw["lengthscale"], "model.prior.lengthscale", keys)
        for name, pair in table.items():
            if pair is not None:
                where = space.feature_index(name)
                scales[where] = _log_normal(pair, "model.prior.lengthscale", name)
    variance = prior.variance
    if raw["signal_variance"] is not None:
        variance = _log_normal(raw["signal_variance"], "model.prior", "signal_variance")
    band_prior = prior.band
    if raw["tie_band"] is not None:
        if band_prior is None:
            fail("model.prior", "tie_band", 'only used with tie_band = "fit"')
        band_prior = _log_normal(raw["tie_band"], "model.prior", "tie_band")
    try:
        return Learning(
            cast(TiesMode, model["ties"]),
            band,
            cast(FitMode, model["fit"]),
            model["refit_every"],
            HyperPrior(tuple(scales), variance, band_prior),
            cast(HyperMode, model["hyper"]),
            tuple(model["hypotheses"]),
            cast(ShareMode, model["share"]),
            cast(WarmFirst, model["warm_first"]),
        )
    except ValueError as exc:
        fail("model", None, str(exc))
