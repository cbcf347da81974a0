"""What the CoSpar loop learns from its answers besides the utilities: ties and hyperparameters.

- ``ties``: ``"drop"`` stores "no preference" answers without modelling them (the paper);
  ``"model"`` makes every answer to a comparison an ordered-probit observation with an
  indifference band (``model/likelihood.py``, :class:`~gaitpref.model.likelihood.OrderedProbit`):
  a preference ``a > b`` has probability ``Phi((d - band) / (sqrt(2) sigma))``, a "no preference"
  ``Phi((d + band) / s) - Phi((d - band) / s)``.  Coactive suggestions stay plain probit
  preferences (``sigma / coactive_weight``, no band): they are not answers to a comparison.
- ``tie_band``: the band in utility units (a number), or None to learn it with the other
  hyperparameters (needs ``fit="evidence"``).
- ``fit``: ``"fixed"`` keeps the config's kernel (the paper); ``"evidence"`` refits lengthscales,
  signal variance (and a learned band) every ``refit_every`` answers by maximising the Laplace
  evidence plus priors (``model/hyperfit.py``), warm-started from the current values.  Single-
  action terms (ratings) take part; ordinal thresholds the config leaves unset are fitted with
  the rest (``Hyperparameters.thresholds``), and the posterior uses the fitted ones.
- ``hyper``: ``"map"`` uses the one fitted kernel; ``"average"`` (needs ``fit="evidence"``)
  also weighs the lengthscale hypotheses ``hypotheses`` (factors of the fitted lengthscales) by
  Laplace evidence x prior at every refit (``model/hypermix.py``): each ask draws a hypothesis
  by weight from the loop's generator and proposes under its posterior, and the recommendation
  is the argmax of the weighted mean.
- ``share``: how a warm start that re-learns the new subject's shared fraction
  (``loop/warm.py``) holds it: ``"map"`` one value chosen by the evidence after every answer
  (``model/share_fit.py``); ``"average"`` a mixture over share hypotheses weighted by evidence
  x prior (``model/share_mix.py``): each ask draws a hypothesis by weight (when the lengthscales
  are not averaged too), the confidence's samples come from the mixture, and the posterior
  in force is the heaviest hypothesis'.  Without a warm start it changes nothing.  The dataclass
  default is ``"map"``; a config's default is ``"average"`` since defaults version 0.6.
- ``warm_first``: a warm-started loop's first trial.  ``"strategy"`` lets the strategy choose
  it, as every trial (the new subject starts alone, so nothing the earlier subjects said
  reaches it); ``"recommended"`` walks the earlier subjects' recommendation first: the argmax,
  among the gaits the loop may propose, of the new subject's posterior mean with their share
  at the population's ``rho`` (``loop/cospar.py``), when that mean is not flat (``rho = 0`` or
  no data: the strategy chooses).  Without a warm start, or with ``[safety] start`` gaits,
  it changes nothing.  The dataclass default is ``"strategy"``; a config's default is
  ``"recommended"`` since defaults version 0.8.

:func:`pair_data` turns a loop's preferences and ties into the arrays the model takes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from gaitpref.checks import is_count, is_number
from gaitpref.feedback import Preference, Tie
from gaitpref.model.evidence import PairData
from gaitpref.model.hyperfit import HyperPrior

TiesMode = Literal["drop", "model"]
FitMode = Literal["fixed", "evidence"]
TIES_MODES: tuple[TiesMode, ...] = ("drop", "model")
FIT_MODES: tuple[FitMode, ...] = ("fixed", "evidence")
HyperMode = Literal["map", "average"]
HYPER_MODES: tuple[HyperMode, ...] = ("map", "average")
ShareMode = Literal["map", "average"]
SHARE_MODES: tuple[ShareMode, ...] = ("map", "average")
WarmFirst = Literal["strategy", "recommended"]
WARM_FIRST: tuple[WarmFirst, ...] = ("strategy", "recommended")
#: The default lengthscale hypotheses of ``hyper = "average"``: factors of the fitted ones.
HYPOTHESES: tuple[float, ...] = (0.5, 0.71, 1.0, 1.41, 2.0)
#: The most lengthscale hypotheses, and the factors one may be (a config's bounds,
#: ``config/schema.py``): with ``hyper = "average"`` every answer refits each of them, so a
#: million of them made every tell a million Laplace fits.
MAX_HYPOTHESES = 15
HYPOTHESIS_FACTORS = (0.01, 100.0)  # (exclusive, inclusive)


@dataclass(frozen=True)
class Learning:
    """How ties and hyperparameters are learned (the defaults are the paper's model)."""

    ties: TiesMode = "drop"
    tie_band: float | None = None
    fit: FitMode = "fixed"
    refit_every: int = 20
    prior: HyperPrior | None = None  # None: model.hyperfit.default_prior
    hyper: HyperMode = "map"
    hypotheses: tuple[float, ...] = HYPOTHESES
    share: ShareMode = "map"
    warm_first: WarmFirst = "strategy"

    def __post_init__(self) -> None:
        if self.ties not in TIES_MODES:
            raise ValueError(f"ties must be one of {', '.join(TIES_MODES)}; got {self.ties!r}")
        if self.fit not in FIT_MODES:
            raise ValueError(f"fit must be one of {', '.join(FIT_MODES)}; got {self.fit!r}")
        if not is_count(self.refit_every) or self.refit_every < 1:
            raise ValueError(f"refit_every must be an integer >= 1, got {self.refit_every!r}")
        object.__setattr__(self, "refit_every", int(self.refit_every))
        if self.tie_band is not None:
            if self.ties == "drop":
                raise ValueError("tie_band is only used with ties = 'model'")
            if not (is_number(self.tie_band) and np.isfinite(self.tie_band) and self.tie_band > 0):
                raise ValueError(f"tie_band must be positive, got {self.tie_band!r}")
        elif self.ties == "model" and self.fit == "fixed":
            raise ValueError("ties = 'model' with fit = 'fixed' needs a tie_band (a number)")
        if self.hyper not in HYPER_MODES:
            raise ValueError(f"hyper must be one of {', '.join(HYPER_MODES)}; got {self.hyper!r}")
        if self.hyper == "average" and self.fit != "evidence":
            raise ValueError("hyper = 'average' needs fit = 'evidence'")
        if (
            isinstance(self.hypotheses, str)
            or not isinstance(self.hypotheses, Sequence | np.ndarray)
            or len(self.hypotheses) == 0
            or not all(is_number(c) and np.isfinite(c) and c > 0 for c in self.hypotheses)
        ):
            raise ValueError(f"hypotheses must be positive numbers, got {self.hypotheses!r}")
        low, high = HYPOTHESIS_FACTORS
        if len(self.hypotheses) > MAX_HYPOTHESES or not all(
            low < c <= high for c in self.hypotheses
        ):
            raise ValueError(
                f"hypotheses must be 1 to {MAX_HYPOTHESES} lengthscale factors in "
                f"({low:g}, {high:g}], got {len(self.hypotheses)}: {self.hypotheses!r}"[:300]
            )
        object.__setattr__(self, "hypotheses", tuple(float(c) for c in self.hypotheses))
        if self.prior is not None and not isinstance(self.prior, HyperPrior):
            raise TypeError(f"prior must be a HyperPrior or None, got {self.prior!r}")
        if len(set(self.hypotheses)) != len(self.hypotheses):
            raise ValueError(f"hypotheses must differ, got {self.hypotheses!r}")
        if self.share not in SHARE_MODES:
            raise ValueError(f"share must be one of {', '.join(SHARE_MODES)}; got {self.share!r}")
        if self.warm_first not in WARM_FIRST:
            raise ValueError(
                f"warm_first must be one of {', '.join(WARM_FIRST)}; got {self.warm_first!r}"
            )

    @property
    def learns_band(self) -> bool:
        return self.ties == "model" and self.tie_band is None

    @property
    def is_paper(self) -> bool:
        """True when the loop behaves exactly as the paper's (ties dropped, kernel fixed)."""
        return self.ties == "drop" and self.fit == "fixed"


def pair_data(
    preferences: Sequence[Preference], ties: Sequence[Tie], tie_noise: float, model_ties: bool
) -> PairData:
    """Observations for the model: preferences (winner first), then ties when modelled.

    Answers to comparisons are banded when ties are modelled; coactive suggestions never are.
    """
    kept_ties = list(ties) if model_ties else []
    first = [p.winner for p in preferences] + [t.first for t in kept_ties]
    second = [p.loser for p in preferences] + [t.second for t in kept_ties]
    sigma = [p.noise for p in preferences] + [tie_noise] * len(kept_ties)
    banded = [model_ties and p.source == "comparison" for p in preferences]
    banded += [True] * len(kept_ties)
    tie = [False] * len(preferences) + [True] * len(kept_ties)
    return PairData(
        np.asarray(first, dtype=np.intp),
        np.asarray(second, dtype=np.intp),
        np.asarray(sigma, dtype=np.float64),
        np.asarray(banded, dtype=bool),
        np.asarray(tie, dtype=bool),
    )
