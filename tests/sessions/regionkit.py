"""The rated scenario of the region-of-avoidance tests of undo and exclusion.

On a 15-gait grid with ``[safety] avoid = ["very bad"]``, seed 2 runs gaits 2, 4, 0, 14, 14 and
then proposes gait 1: trial 1 (gait 2) rated "good" makes gait 1, next to it, look safe enough
to propose, though its other neighbours are "very bad".  Take that rating out of the model
(exclude trial 1) and gait 1 lies in the region.
"""

from __future__ import annotations

from gaitpref import Rating, Session
from gaitpref.config import ExperimentConfig, parse_config

CONFIG = """
name = "rated-region"
[space.step_length]
min = 0.08
max = 0.18
num = 15
[model]
lengthscale = 0.03
signal_variance = 0.005
noise = 0.02
fit = "fixed"
[cospar]
seed = 2
strategy = "self-sparring"
[feedback.rating]
labels = ["very bad", "bad", "okay", "good"]
[safety]
avoid = ["very bad"]
lambda = 1.0
"""
#: the gaits the first six queries propose (the sixth while trial 1's rating is in the model)
GAITS = (2, 4, 0, 14, 14, 1)


def config() -> ExperimentConfig:
    return parse_config(CONFIG)


def rate_trials(s: Session, trials: int) -> None:
    """Answer ``trials`` queries with a rating each: trial 1 "good", the gaits below 5 "very
    bad", the others "okay"."""
    for trial in range(1, trials + 1):
        q = s.next_query()
        a = q.actions[0]
        label = "good" if trial == 1 else "very bad" if a < 5 else "okay"
        s.answer(q.id, [Rating(a, label)])
