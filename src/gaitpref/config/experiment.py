"""The parsed experiment config (:class:`ExperimentConfig`) and the loop it makes."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from gaitpref.config.generator import GeneratorSpec
from gaitpref.config.schema import DEFAULTS_VERSION, EARLIER_DEFAULTS
from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.learning import Learning
from gaitpref.loop.line import LineCoSpar
from gaitpref.loop.lines import LineSettings
from gaitpref.loop.safety import Safety
from gaitpref.loop.stopping import StopRule
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.ordinal import Ordinal
from gaitpref.space import Space
from gaitpref.strategies import make_strategy

if TYPE_CHECKING:
    from gaitpref.gaits.library import GaitLibrary


@dataclass(frozen=True)
class ExperimentConfig:
    """A parsed experiment config and the exact text it came from.

    ``defaulted`` names the keys (``"cospar.buffer"``) the text left to the defaults of
    ``defaults_version`` (``gaitpref.config.schema``).
    """

    name: str
    space: Space
    kernel: SquaredExponential
    noise: float
    n: int
    buffer: int
    coactive_weight: float
    seed: int
    text: str = field(repr=False)
    description: str = ""
    strategy: str = "self-sparring"
    learning: Learning = field(default_factory=Learning)
    sampler: str = "auto"
    library: GaitLibrary | None = field(default=None, repr=False, compare=False)
    library_path: str | None = None
    #: the folder a relative ``[gaits].library`` path was taken from (resolved; None when the
    #: config names no library): sessions store it, a path with ``..`` or through a link cannot
    #: be traced back to it from the library's resolved path
    base_dir: str | None = field(default=None, repr=False, compare=False)
    generator: GeneratorSpec | None = None  # [gaits] generator: gaits made on demand
    strategy_settings: dict[str, Any] = field(default_factory=dict)
    defaulted: frozenset[str] = field(default=frozenset(), repr=False, compare=False)
    defaults_version: str = DEFAULTS_VERSION
    ordinal: Ordinal | None = None  # [feedback.rating]
    safety: Safety = field(default_factory=Safety)  # [safety]
    stop: StopRule = field(default_factory=StopRule)  # [stop]
    subspace: str = "grid"  # [cospar] subspace, resolved: "grid" or "line" (issue 13)
    # line_points, line_direction, line_count
    line: LineSettings = field(default_factory=LineSettings)

    @property
    def sha256(self) -> str:
        """Hash of the config text as given (sessions store it to detect changes)."""
        return hashlib.sha256(self.text.encode()).hexdigest()

    @property
    def library_sha256(self) -> str | None:
        """Hash of the gait library file, if the config names one."""
        if self.library_path is None:
            return None
        return hashlib.sha256(Path(self.library_path).read_bytes()).hexdigest()

    @property
    def relies_on_changed_defaults(self) -> bool:
        """Whether the text leaves to the defaults a key whose default changed between versions.

        A session stores :attr:`defaults_version` then, so that it replays with the same values.
        """
        changed = {
            f"{table}.{key}"
            for old in EARLIER_DEFAULTS.values()
            for table in old
            for key in old[table]
        }
        return bool(self.defaulted & changed)

    def gait_id(self, index: int) -> str | None:
        """The gait id of grid action ``index`` when the config names a gait library."""
        return None if self.library is None else self.library.gait_id(index)

    def make_loop(self, seed: int | np.random.Generator | None = None) -> CoSpar:
        """A fresh :class:`CoSpar` loop with these settings (``seed`` overrides the config's):
        a :class:`LineCoSpar` on the line path."""
        if self.subspace == "line":
            return LineCoSpar(
                self.space, self.kernel, self.noise, line=self.line, **self._loop(seed)
            )
        return CoSpar(self.space, self.kernel, self.noise, **self._loop(seed))

    def _loop(self, seed: int | np.random.Generator | None = None) -> dict[str, Any]:
        return dict(
            n=self.n,
            buffer=self.buffer,
            coactive_weight=self.coactive_weight,
            seed=self.seed if seed is None else seed,
            strategy=make_strategy(self.strategy, **self.strategy_settings),
            learning=self.learning,
            sampler=self.sampler,
            ordinal=self.ordinal,
            safety=self.safety,
        )
