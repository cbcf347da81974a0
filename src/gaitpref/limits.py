"""The largest counts a simulated run takes, from the command line or the API.

The project's rule: no request, config or file may make a process allocate without bound or
spin forever.  A simulated run executes every trial it is asked for (a session's ``[stop]
max_trials`` is a rule that may never be reached; a simulation's ``--trials`` is work done),
and a study keeps every run's per-trial results in memory before it writes them as its run
table, so each count below is refused past its maximum, naming the option or argument, before
anything runs.  The maxima are far past any study a lab runs (the paper's Fig. 4 study is
7 settings x 100 runs x 150 trials, 105,000 trials in all).

Plain numbers with no imports: the command line reads them when it declares its options
(``typer.Option(max=...)``), before NumPy is loaded (``tests/cli/test_startup.py``).
"""

from __future__ import annotations

#: Trials of one simulated run (``gaitpref simulate``/``demo``/``bench ... --trials``,
#: ``Study.trials``, ``run_simulation``): each trial is one ask and one refit over all the
#: answers so far, so 10**12 ran until the memory was full (a random-selection arm asked NumPy
#: for 7.28 TiB at once).
MAX_TRIALS = 100_000
#: The most runs a study holds (settings x objectives x seeds), and a bench's ``--runs``: its
#: tasks and results are kept in memory (``bench compass-gait --runs 100000000`` filled the
#: memory before its first run).
MAX_RUNS = 100_000
#: Trials in all of a study's runs together (runs x trials; its runs are at most
#: :data:`MAX_RUNS`): each is a row of the run table,
#: held in memory (about 100 bytes a row: 1 GB at this bound) before it is written.
MAX_STUDY_TRIALS = 10_000_000
#: The largest seed: what a config's ``[cospar] seed`` and a session's seed hold (a signed
#: 64-bit integer, the database's and the run table's column); NumPy took any integer, so
#: ``--seed 2**200`` ran, and a run seed past it failed when the finished runs were tabulated.
MAX_SEED = 2**63 - 1
#: The most parallel workers (``--jobs``): local processes (joblib starts every one asked for,
#: each with its own NumPy; a local Ray runtime gets as many CPUs), never more than the runs.
MAX_JOBS = 256
#: The most posterior panels ``bench compass-gait --iterations`` draws (one figure panel each).
MAX_SNAPSHOTS = 16
#: The most visited (gait, subject) nodes ``bench population``'s warm runs may hold: subjects x
#: the gaits each may visit (``min(A, trials + n - 1)``).  A warm run's Laplace fit is dense in
#: them (``model/population.py``), an ``m x m`` matrix (10,000 nodes: 800 MB) refitted after
#: every answer; the studies in ``docs/results/population`` hold under 1,000.
MAX_POPULATION_NODES = 10_000
#: The authors' objectives of the paper's Fig. 4 (``gaitpref.data.paper_objectives``): ``bench
#: paper-2d --runs`` runs objective k in run k, so it takes at most this many.
PAPER_OBJECTIVES = 100
#: The largest partial file a resumed sweep reads (``--resume``: ``OUT/runs.partial.csv``, a
#: bench's ``--partial``): it is read whole, and a study's run table is at most about 1 GB
#: (:data:`MAX_STUDY_TRIALS` rows of about 100 bytes); a larger file is refused, not read.
MAX_PARTIAL_BYTES = 2 * 1024**3

__all__ = [
    "MAX_JOBS",
    "MAX_PARTIAL_BYTES",
    "MAX_POPULATION_NODES",
    "MAX_RUNS",
    "MAX_SEED",
    "MAX_SNAPSHOTS",
    "MAX_STUDY_TRIALS",
    "MAX_TRIALS",
    "PAPER_OBJECTIVES",
]
