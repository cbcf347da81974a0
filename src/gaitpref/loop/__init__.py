"""The CoSpar loop (the paper's Algorithm 1) behind ask/tell, and what it learns besides utilities.

- :class:`CoSpar` (``cospar.py``): ask for a query, tell it feedback records of any registered kind.
- :class:`Learning` (``learning.py``): ties and hyperparameter refits.
"""

from gaitpref.loop.cospar import Answer, CoSpar, Query, QueryError
from gaitpref.loop.learning import FIT_MODES, TIES_MODES, FitMode, Learning, TiesMode, pair_data
from gaitpref.loop.safety import Safety

__all__ = [
    "FIT_MODES",
    "TIES_MODES",
    "Answer",
    "CoSpar",
    "FitMode",
    "Learning",
    "Query",
    "QueryError",
    "Safety",
    "TiesMode",
    "pair_data",
]
