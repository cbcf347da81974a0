"""A warm start built by hand names a bad argument where it is given.

Before: ``relearn_every = 2.5`` re-learned the share every 5 answers (``answers % 2.5``), a gate
of NaN never let the evidence favour sharing (the share stayed 0, silently), rho given as
``"0.5"`` or ``True`` was read as 0.5 or 1 (``float(rho)``), and a ``LogitNormal`` of strings
was a NumPy TypeError.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from gaitpref import Feature, SquaredExponential
from gaitpref.loop.warm import WarmStart, warm_data
from gaitpref.model import LogitNormal, PopulationModel
from gaitpref.space import Space

SPACE = Space([Feature.linspace("a", 0.0, 1.0, 5)])
DATA = warm_data(SPACE, [[]])


def _warm(**changes: Any) -> WarmStart:
    fields: dict[str, Any] = {"data": DATA, "rho": 0.5, "subjects": 1}
    return WarmStart(**{**fields, **changes})


@pytest.mark.parametrize(
    ("changes", "error", "message"),
    [
        ({"relearn_every": 2.5}, ValueError, "relearn_every must be an integer >= 0, got 2.5"),
        ({"relearn_every": -1}, ValueError, "relearn_every must be an integer >= 0, got -1"),
        ({"relearn_every": "2"}, ValueError, "relearn_every must be an integer"),
        ({"subjects": -1}, ValueError, "subjects must be an integer >= 0, got -1"),
        ({"subjects": 1.0}, ValueError, "subjects must be an integer"),
        ({"gate": np.nan}, ValueError, "gate must be None or a number of nats >= 0, got nan"),
        ({"gate": -1.0}, ValueError, "gate must be None or a number of nats"),
        ({"rho": "0.5"}, ValueError, r"rho must lie in \[0, 1\], got '0.5'"),
        ({"rho": True}, ValueError, r"rho must lie in \[0, 1\], got True"),
        ({"share": "0.1"}, ValueError, "rho must lie in"),
        ({"share_prior": 0.5}, TypeError, "share_prior must be a LogitNormal or None, got 0.5"),
        ({"data": [[0, 1]]}, TypeError, "data must be a PairData"),
        ({"singles": [1]}, TypeError, "singles must be a SingleData or None"),
    ],
)
def test_bad_warm_start_arguments_are_named(
    changes: dict[str, Any], error: type, message: str
) -> None:
    with pytest.raises(error, match=message):
        _warm(**changes)


def test_numbers_of_every_kind() -> None:
    warm = _warm(rho=np.float32(0.25), subjects=np.int64(2), relearn_every=np.uint8(5), gate=1)
    assert (warm.rho, warm.subjects, warm.relearn_every) == (0.25, 2, 5)
    assert type(warm.subjects) is int and warm.relearns(10) and not warm.relearns(7)


def test_population_numbers_are_numbers() -> None:
    kernel = SquaredExponential(0.3, 1.0, 1e-6)
    with pytest.raises(ValueError, match=r"rho must lie in \[0, 1\], got '0.5'"):
        PopulationModel(SPACE, kernel, "0.5", 0.1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"rho's prior median must lie in \(0, 1\), got '0.5'"):
        LogitNormal("0.5", 1.0)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="rho's prior sd must be >= 0, got True"):
        LogitNormal(0.5, True)


def test_a_population_model_checks_its_parts() -> None:
    # a kernel of another type or of the wrong lengthscale count failed at the first posterior
    kernel = SquaredExponential(0.3, 1.0, 1e-6)
    with pytest.raises(TypeError, match=r"kernel must be a gaitpref\.SquaredExponential"):
        PopulationModel(SPACE, "rbf", 0.5, 0.1)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"space must be a gaitpref\.Space"):
        PopulationModel([0.0, 1.0], kernel, 0.5, 0.1)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"ordinal must be a gaitpref\.Ordinal or None"):
        PopulationModel(SPACE, kernel, 0.5, 0.1, ordinal=3)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="kernel has 2 lengthscales but the space has 1"):
        PopulationModel(SPACE, SquaredExponential((0.3, 0.4), 1.0), 0.5, 0.1)
