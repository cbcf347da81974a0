"""Every error gaitpref raises on purpose derives from :class:`GaitprefError`.

The families below are where callers (the CLI, the terminal, the console) map errors to messages
and status codes, in one place each.  Each class also derives from the built-in exception its
callers caught before 0.2 (``ValueError``, ``RuntimeError``, ...), so ``except ValueError`` keeps
working.  Storage errors live in :mod:`gaitpref.storage` and derive from :class:`StorageError`.

=========================  ====================================================================
family                     raised when
=========================  ====================================================================
:class:`ConfigError`       a config (TOML, dict or web form) is not valid; names table and key
:class:`ModelError`        the numerics cannot go on (:class:`ConvergenceError`, a prior that is
                           not positive definite, :class:`NoSafeGaitError`: no gait is safe,
                           :class:`InfeasibleProposalsError`: an ask's proposals had no gait)
:class:`ShortLinesError`   a :class:`NoSafeGaitError`: no line drawn holds the ``n`` points
:class:`FeedbackError`     an answer does not fit its query; nothing was changed
:class:`QueryError`        an answer to a query that is unknown, stale or already answered
:class:`SessionError`      a session's state refuses an operation, its log does not replay, an
                           export cannot be read
:class:`StorageError`      a database cannot be read or written; nothing was written
:class:`GaitError`         a gait library, a gait generator or a gait simulation failed
                           (:class:`GaitGeneratorFaultError`: the generator raised an
                           unexpected error making a gait)
``RunError``               a simulated sweep was stopped by a run (``gaitpref.simulate.partial``;
                           ``ResumeError``: a partial file that is not the sweep's to resume,
                           ``gaitpref.simulate.resume``)
=========================  ====================================================================
"""

from __future__ import annotations


class GaitprefError(Exception):
    """Base of every error gaitpref raises on purpose: its message names the problem."""


class ConfigError(GaitprefError, ValueError):
    """A config that cannot be used; the message names the table and the key.

    ``table`` (``"model"``, ``"space.step_length"``, ``"cospar.strategy_settings"``) and ``key``
    say where, when the problem has a place (``None`` for a file that is not TOML at all); the
    message reads ``[table].key: what is wrong and what is allowed``.
    """

    def __init__(self, message: str, *, table: str | None = None, key: str | None = None) -> None:
        super().__init__(message)
        self.table = table
        self.key = key


class ModelError(GaitprefError):
    """The model's numerics cannot go on."""


class ConvergenceError(ModelError, RuntimeError):
    """The Newton iteration for the Laplace mode did not converge."""


class PriorNotPositiveDefiniteError(ModelError, ValueError):
    """``K_VV`` could not be factorised: the kernel needs a (larger) jitter."""


class NoSafeGaitError(ModelError, RuntimeError):
    """Every gait is in the region of avoidance or near a gait flagged unsafe: the loop proposes
    nothing rather than a gait it should avoid."""


class InfeasibleProposalsError(NoSafeGaitError):
    """Gaits made on demand: one ask made ``[gaits] max_infeasible`` proposals (or a few more,
    in its last proposal) whose gait could not be made, and stopped without proposing.  Each is
    logged (``gait_infeasible``) and avoided, so asking again goes on from there; ``infeasible``
    is how many this ask made, ``limit`` the config's bound."""

    def __init__(self, message: str, *, infeasible: int = 0, limit: int = 0) -> None:
        super().__init__(message)
        self.infeasible = infeasible
        self.limit = limit


class ShortLinesError(NoSafeGaitError, ValueError):
    """The line path: none of the lines an ask drew holds the query's ``n`` points (with the
    points so far) and a point that may be proposed; a line snapped to a few grid values of
    discrete features may hold fewer (``loop/line.py``).  Nothing was proposed.  A
    :class:`NoSafeGaitError` (no gait may be proposed: the terminal pauses, the console answers
    409 and says why) and, as before it had a class, a ``ValueError``."""


class FeedbackError(GaitprefError, ValueError):
    """An answer that cannot be taken; nothing was changed."""


class PriorFromError(GaitprefError, ValueError):
    """A warm start's ``prior_from`` names a session or subject that is not there, or one run
    on another grid, or one that cannot be rebuilt from the database, or more answers than a
    warm start takes; nothing was created."""


class QueryError(GaitprefError, ValueError):
    """A ``tell`` for a query that is unknown, stale or already answered; nothing was changed."""


class SessionError(GaitprefError, RuntimeError):
    """A session operation that cannot be done."""


class SessionStateError(SessionError):
    """The session's state does not allow this (finished, paused, nothing to undo, ...)."""


class ReplayError(SessionError):
    """Rebuilding a session from its log did not give what the log says; nothing was changed."""


class ExportError(SessionError):
    """An export folder that cannot be written or read back."""


class StorageError(GaitprefError, RuntimeError):
    """A storage operation that could not be done; nothing was written."""


class GaitError(GaitprefError):
    """Gait generation or a gait library failed."""


class GaitLibraryError(GaitError, ValueError):
    """A gait library file that cannot be read, or a library that does not fit its config."""


class GaitGeneratorError(GaitError, ValueError):
    """A gait generator that is unknown or cannot make gaits over the given features."""


class GaitGeneratorFaultError(GaitError, RuntimeError):
    """A gait generator raised an unexpected error making a gait (a fault in the generator or
    its numerics, not a gait it found infeasible); raised from the generator's error."""


class SimulationError(GaitError, RuntimeError):
    """A gait simulation that cannot go on (a fall, a non-finite state, no impact)."""


__all__ = [
    "ConfigError",
    "ConvergenceError",
    "ExportError",
    "FeedbackError",
    "GaitError",
    "GaitGeneratorError",
    "GaitGeneratorFaultError",
    "GaitLibraryError",
    "GaitprefError",
    "InfeasibleProposalsError",
    "ModelError",
    "NoSafeGaitError",
    "PriorNotPositiveDefiniteError",
    "QueryError",
    "ReplayError",
    "SessionError",
    "SessionStateError",
    "ShortLinesError",
    "SimulationError",
    "StorageError",
]
