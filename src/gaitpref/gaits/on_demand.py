"""Gaits on demand: a point gets its gait when first proposed, warm-started from the nearest.

The paper's future work ("generating new gaits" rather than a precomputed library; issue 13, item
4).  :class:`OnDemandGaits` is one session's view: the gaits it has made, in the order it made
them.  The gait of a parameter vector is, in turn,

1. the one this session already made for the same gait id;
2. the one its log carries, when the session is replayed (``recorded``: the session layer
   checks it against the log and hands it over; a recorded gait is never made again; one
   that fails :func:`made_gait_problem` is used as logged, so that replay follows the log, but is
   neither cached nor a warm start, with a :class:`~gaitpref.gaits.gait_cache.GaitCacheWarning`);
3. the cached one (:class:`~gaitpref.gaits.gait_cache.GaitCache`, content-addressed by the
   generator's key), used as it is;
4. a new one from the generator, warm-started from the nearest *feasible* gait this session made
   before (Euclidean distance with each feature divided by its range, as for the unsafe radius;
   the earliest of equally near ones), then cached.  A generator that raises an error other
   than gaitpref's own (a bug, a ``LinAlgError``) raises a
   :class:`~gaitpref.errors.GaitGeneratorFaultError` naming it, the gait and that error; nothing
   is cached or remembered, so the same gait is made again when next asked for.  So is a
   generator's document (:meth:`~gaitpref.gaits.generator.GaitGenerator.document`) that is not
   JSON (a numpy array, a set, NaN, a key that is not text:
   :func:`~gaitpref.gaits.json_document.document_problem`), or one that uses a field of the
   gait cache's files (``format``, ``key``, ``gait``...: ``gait_cache.FILE_FIELDS``, among which
   the document is written), checked when the gait is named, before its key is hashed or
   anything is cached.

On a space with continuous features two proposed points may agree to the generator's displayed
digits (``compass-hzd`` rounds to 3 decimals), so there the id is the generator's followed by
``#`` and 8 hex digits of the SHA-256 of the point's float64 bytes (:func:`exact_gait_id`); grid
ids stay the generator's, so sessions logged before replay unchanged.

Because the warm start depends only on the session's own earlier gaits, a session that replays
a log without its gaits (``gait_made`` version 1) and with an empty cache makes the same gaits
again in the same order (on a machine that rounds as the recording one did).

Notation: ``d`` features; a parameter vector is ``(d,)`` in the features' units.
"""

from __future__ import annotations

import hashlib
import math
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np

from gaitpref.checks import char_name, hidden_in
from gaitpref.errors import GaitGeneratorFaultError, GaitprefError
from gaitpref.gaits.gait import Gait
from gaitpref.gaits.gait_cache import (
    FILE_FIELDS,
    CachedGait,
    GaitCache,
    GaitCacheWarning,
    file_field_in,
)
from gaitpref.gaits.generator import GaitGenerator
from gaitpref.gaits.json_document import document_problem
from gaitpref.gaits.library import MAX_GAIT_ID, feasible_gait_problem
from gaitpref.gaits.library_io import GAIT_NUMBERS
from gaitpref.space import FloatArray

#: the longest solver message a made gait may carry (it is logged, and shown when infeasible)
MAX_GAIT_MESSAGE = 2000


def _kind(value: object) -> str:
    """``value``'s type as a message names it: ``numpy.bool``, ``int``."""
    kind = type(value)
    return kind.__name__ if kind.__module__ == "builtins" else f"{kind.__module__}.{kind.__name__}"


def made_gait_problem(gait: object, step_length: float | None) -> str | None:
    """What makes a generator's result unfit to be logged and shown, or None: not a
    :class:`Gait`; a ``feasible`` that is not a bool, a ``status`` that is not an int, a
    ``message`` that is not text of at most :data:`MAX_GAIT_MESSAGE` characters without
    hidden characters; a step length that is not a finite number (a positive one, when
    feasible) or not the one asked for (``step_length``); numbers that are not numbers,
    coefficients or an orbit of the wrong shape; and, for a gait called feasible, anything
    not finite, ``delta^2`` outside ``(0, 1)``, a step duration that is not positive, an empty
    phase or a constraint residual (normal force, friction ratio) that is not a number."""
    if not isinstance(gait, Gait):
        return f"it returned a {_kind(gait)}, not a Gait"
    if not isinstance(gait.feasible, bool):
        return f"feasible is a {_kind(gait.feasible)}, not a bool"
    if isinstance(gait.status, bool) or not isinstance(gait.status, int):
        return f"status is a {_kind(gait.status)}, not an int"
    if not isinstance(gait.message, str):
        return f"message is a {_kind(gait.message)}, not text"
    if len(gait.message) > MAX_GAIT_MESSAGE:
        return f"message has {len(gait.message):,} characters, more than {MAX_GAIT_MESSAGE}"
    hidden = hidden_in(gait.message)
    if hidden:
        return f"message holds {char_name(hidden[0][1])}"
    length = gait.step_length
    if isinstance(length, bool) or not isinstance(length, int | float) or not math.isfinite(length):
        return f"step length {length!r} is not a finite number"
    if gait.feasible and length <= 0:  # an infeasible one may be a point no gait can pose
        return f"feasible gait with step length {length!r}, not a positive one"
    if step_length is not None and not math.isclose(length, step_length, rel_tol=1e-9):
        return f"step length {length!r} is not the {step_length!r} asked for"
    for name in GAIT_NUMBERS:
        value = getattr(gait, name)
        if isinstance(value, bool) or not isinstance(value, int | float):
            return f"{name} is a {_kind(value)}, not a number"
    if gait.alpha.ndim != 2 or gait.alpha.shape[0] != 1 or gait.alpha.shape[1] < 2:
        return f"alpha has shape {gait.alpha.shape}, not (1, M + 1)"
    if gait.orbit_state.shape != (4,):
        return f"orbit_state has shape {gait.orbit_state.shape}, not (4,)"
    if not gait.feasible:
        return None
    problem = feasible_gait_problem(gait)
    if problem is not None:
        return problem
    if gait.step_duration <= 0 or gait.phase_end == gait.phase_start:
        return "feasible gait with a step duration that is not positive or an empty phase"
    if not (math.isfinite(gait.min_normal_force) and math.isfinite(gait.max_friction_ratio)):
        return "feasible gait whose constraint residuals (normal force, friction) are not finite"
    if gait.max_friction_ratio < 0:
        return "feasible gait with a negative friction ratio"
    return None


@dataclass(frozen=True, eq=False)
class MadeGait:
    """The gait of ``vector``: its key, id, and the key it was warm-started from (if any);
    ``from_cache``: found (in the cache or the session's log), not made."""

    key: str
    vector: FloatArray
    gait: Gait
    gait_id: str
    warm_start: str | None
    from_cache: bool

    @property
    def feasible(self) -> bool:
        return self.gait.feasible


def exact_gait_id(generator: GaitGenerator, vector: FloatArray) -> str:
    """``generator``'s id of ``vector`` and ``#`` + 8 hex digits of its float64 bytes' SHA-256."""
    arr = np.ascontiguousarray(generator.check(vector), dtype="<f8")
    return f"{generator.gait_id(arr)}#{hashlib.sha256(arr.tobytes()).hexdigest()[:8]}"


class OnDemandGaits:
    """One session's gaits made on demand by ``generator``; ``ranges`` scale the distances;
    ``exact`` ids (:func:`exact_gait_id`) for a space with continuous features."""

    def __init__(
        self,
        generator: GaitGenerator,
        cache: GaitCache,
        ranges: Sequence[float],
        *,
        exact: bool = False,
    ):
        scale = np.asarray(ranges, dtype=np.float64)
        if scale.shape != (len(generator.features),):
            raise ValueError(f"ranges needs {len(generator.features)} values, got {scale.shape}")
        self.generator = generator
        self.cache = cache
        self.scale = np.where(scale > 0, scale, 1.0)
        self.exact = exact
        self._by_id: dict[str, MadeGait] = {}  # a label (step width) shares its gait's key
        self._feasible: list[MadeGait] = []

    @property
    def made(self) -> list[MadeGait]:
        """Every gait this session has made or looked up, in order."""
        return list(self._by_id.values())

    def gait_id(self, vector: FloatArray) -> str:
        """The id shown and logged for ``vector``'s gait."""
        if self.exact:
            return exact_gait_id(self.generator, vector)
        return self.generator.gait_id(vector)

    def nearest(self, vector: FloatArray) -> MadeGait | None:
        """The feasible gait made so far nearest to ``vector`` (None: none yet)."""
        if not self._feasible:
            return None
        points = np.stack([m.vector for m in self._feasible])
        d2 = np.sum(((points - vector) / self.scale) ** 2, axis=1)
        return self._feasible[int(np.argmin(d2))]

    def get(
        self, vector: FloatArray, recorded: Callable[[str], CachedGait | None] | None = None
    ) -> tuple[MadeGait, bool]:
        """The gait of ``vector`` and whether it is new to this session; ``recorded(key)``,
        called only for a gait new to the session, gives the one a log carries (None: none).

        An error of the generator other than gaitpref's own (a bug, a ``LinAlgError`` of numpy
        or scipy) is a :class:`~gaitpref.errors.GaitGeneratorFaultError` naming the generator,
        the gait and the error, raised from it (``KeyboardInterrupt`` and the like pass
        unchanged), as is a document of the gait that is not JSON, naming where; nothing of
        that gait is cached or remembered."""
        with self._faults(f"naming the gait of {_shown(vector)}"):
            vec = self.generator.check(vector)
            name = self.gait_id(vec)
            self._check_name(name, vec)
            document = self.generator.document(vec)
            self._check_document(document, name, vec)
            key = self.generator.key(vec)
        known = self._by_id.get(name)
        if known is not None:
            return known, False
        logged = None if recorded is None else recorded(key)
        unfit = None if logged is None else made_gait_problem(logged.gait, self._asked(vec, name))
        if unfit is not None:  # replayed as logged, but neither cached nor a warm start
            self._unfit_logged(recorded, key, name, unfit)
        cached = logged if logged is not None else self._usable(self.cache.get(key), vec, name)
        if logged is not None and unfit is None and self.cache.get(key) is None:
            self.cache.put(logged, document)
        if cached is not None:
            made = MadeGait(key, vec, cached.gait, name, cached.warm_start, True)
        else:
            warm = self.nearest(vec)
            with self._faults(f"making gait {name}"):
                gait = self.generator.make(vec, None if warm is None else warm.gait)
            problem = made_gait_problem(gait, self._asked(vec, name))
            if problem is not None:  # never logged, cached or shown
                raise GaitGeneratorFaultError(
                    f"the gait generator {self.generator.name!r} made gait {name} "
                    f"{_shown(vec)} unfit to use: {problem}; nothing of that gait is cached "
                    "(an error in the generator, not a gait found infeasible)"
                )
            made = MadeGait(key, vec, gait, name, None if warm is None else warm.key, False)
            self.cache.put(CachedGait(key, gait, made.warm_start), document)
        self._by_id[name] = made
        if made.feasible and unfit is None:
            self._feasible.append(made)
        return made, True

    def _unfit_logged(self, recorded: object, key: str, name: str, problem: str) -> None:
        """A :class:`~gaitpref.gaits.gait_cache.GaitCacheWarning` that the gait ``recorded``
        (a session's log, on replay) carries for ``key`` fails :func:`made_gait_problem`: replay
        follows the log, but the gait is not cached nor warm-starts another, so a later ask of
        the point from the cache makes it afresh."""
        where = getattr(recorded, "handed_out", None) or "the session's log"
        warnings.warn(
            f"{where}: the logged gait {name} (key {key}) is unfit to use: {problem}; the "
            "session replays as logged, but that gait is not put into the gait cache nor used "
            "as a warm start: an ask of that point that is not this session's makes it afresh",
            GaitCacheWarning,
            stacklevel=2,
        )

    def _asked(self, vec: FloatArray, name: str) -> float | None:
        """The step length the generator's parameters ask for at ``vec`` (None: none)."""
        with self._faults(f"describing gait {name}"):
            asked = self.generator.parameters(vec).get("step_length")
            return None if asked is None else float(asked)

    def _usable(self, entry: CachedGait | None, vec: FloatArray, name: str) -> CachedGait | None:
        """``entry`` unless its gait is unfit to use (:func:`made_gait_problem`: a cache file
        edited, or written by a generator before its results were checked): then None, and the
        gait is made again, as for an unreadable entry."""
        if entry is None or made_gait_problem(entry.gait, self._asked(vec, name)) is not None:
            return None
        return entry

    def _check_name(self, name: object, vec: FloatArray) -> None:
        """A :class:`~gaitpref.errors.GaitGeneratorFaultError` when the generator's id of the
        gait at ``vec`` is not text of 1 to :data:`~gaitpref.gaits.library.MAX_GAIT_ID`
        characters without hidden ones (it is shown with each trial and logged)."""
        if (
            isinstance(name, str)
            and 0 < len(name) <= MAX_GAIT_ID
            and not hidden_in(name, name=True)
        ):
            return
        what = (
            f"a {_kind(name)}"
            if not isinstance(name, str)
            else f"{len(name):,} characters"
            if not 0 < len(name) <= MAX_GAIT_ID
            else f"text holding {char_name(hidden_in(name, name=True)[0][1])}"
        )
        raise GaitGeneratorFaultError(
            f"the gait generator {self.generator.name!r} named the gait {_shown(vec)} with "
            f"{what}: a gait id is text of 1 to {MAX_GAIT_ID} characters, without control, "
            "format or line-break characters (an error in the generator)"
        )

    def _check_document(self, document: Any, name: str, vec: FloatArray) -> None:
        """A :class:`~gaitpref.errors.GaitGeneratorFaultError` when the generator's ``document``
        of gait ``name`` (at ``vec``) is not JSON that reads back as it is
        (:func:`~gaitpref.gaits.json_document.document_problem`), naming where, or uses one
        of the gait cache file's own fields (``gait_cache.FILE_FIELDS``), naming it."""
        problem = document_problem(document)
        if problem is not None:
            raise GaitGeneratorFaultError(
                f"the gait generator {self.generator.name!r} described gait {name} "
                f"{_shown(vec)} with a document that is not JSON: {problem} (a gait's document "
                "holds only text, finite numbers, true, false, null, lists and objects with text "
                "keys); nothing of that gait is cached (an error in the generator, not a gait "
                "found infeasible)"
            )
        field = file_field_in(document)
        if field is not None:
            raise GaitGeneratorFaultError(
                f"the gait generator {self.generator.name!r} described gait {name} "
                f"{_shown(vec)} with a document that has the field {field!r}, one of the gait "
                f"cache's own ({', '.join(FILE_FIELDS)}): a generator's document may add fields "
                "of its own, but none of those; nothing of that gait is cached (an error in the "
                "generator, not a gait found infeasible)"
            )

    @contextmanager
    def _faults(self, doing: str) -> Iterator[None]:
        """An error other than gaitpref's own raised by the generator while ``doing``, as a
        :class:`~gaitpref.errors.GaitGeneratorFaultError` saying so, raised from it."""
        try:
            yield
        except GaitprefError:
            raise
        except Exception as exc:
            said = str(exc).strip()
            what = f"{type(exc).__name__}: {said}" if said else type(exc).__name__
            raise GaitGeneratorFaultError(
                f"the gait generator {self.generator.name!r} failed {doing}: {what} "
                "(an error in the generator, not a gait found infeasible)"
            ) from exc


def _shown(vector: FloatArray) -> str:
    """``vector`` as ``(0.4, 0.2)`` for a message (its repr if it is not numbers)."""
    try:
        return "(" + ", ".join(f"{float(v):g}" for v in np.ravel(vector)) + ")"
    except (TypeError, ValueError):
        return repr(vector)


__all__ = ["MadeGait", "OnDemandGaits", "exact_gait_id"]
