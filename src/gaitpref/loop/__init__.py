"""The CoSpar loop (the paper's Algorithm 1) behind ask/tell, and what it learns besides utilities.

- :class:`CoSpar` (``cospar.py``): ask for a query, tell it feedback records of any registered kind.
- :class:`Learning` (``learning.py``): ties and hyperparameter refits.
- :class:`LineCoSpar` (``line.py``, ``lines.py``): the line path for continuous spaces and grids
  past memory (LineCoSpar, Tucker et al. IROS 2020), its :class:`LineSettings` and :class:`Line`.
"""

from gaitpref.loop.cospar import Answer, CoSpar, Query, QueryError, as_records
from gaitpref.loop.learning import FIT_MODES, TIES_MODES, FitMode, Learning, TiesMode, pair_data
from gaitpref.loop.line import LineCoSpar
from gaitpref.loop.lines import Line, LineSettings
from gaitpref.loop.safety import Safety

__all__ = [
    "FIT_MODES",
    "TIES_MODES",
    "Answer",
    "CoSpar",
    "FitMode",
    "Learning",
    "Line",
    "LineCoSpar",
    "LineSettings",
    "Query",
    "QueryError",
    "Safety",
    "TiesMode",
    "as_records",
    "pair_data",
]
