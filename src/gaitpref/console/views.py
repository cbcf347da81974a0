"""What the console's pages show, as plain values: gaits, answer choices, keyboard shortcuts.

Nothing here touches a session: these functions turn grid indices into what an operator reads
(feature values with units, a gait id, "slightly longer"), lay out the answer form of a query,
and read that form back into the triples of :meth:`gaitpref.CoSpar.tell`.

Form fields of an answer (stateless: a field names what it answers, the query id is checked
by the session):

- ``cmp-<i>-<j>``: ``first`` | ``second`` | ``none``, comparing grid actions ``i`` and ``j``;
- ``sug-<a>-<feature>``: ``+big`` | ``+small`` | ``-small`` | ``-big`` | empty (no suggestion)
  for executed action ``a``;
- ``rate-<a>``: the rating of executed action ``a``, ``1..K`` (the config's categories, worst
  first) or empty (not rated; read by :mod:`gaitpref.console.answers`).

Keyboard: comparisons ``1`` (first), ``2`` (second), ``0`` (no preference); once every
comparison is answered the digits ``1..K`` rate the gait; suggestions per feature row
``Q W E R T`` / ``A S D F G`` / ``Z X C V B`` (from "more" to "less"); ``N`` opens the last
trial's unsafe flag (:data:`FLAG_KEY`).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace

from gaitpref.console.answers import is_rating_field
from gaitpref.console.errors import InputError, quoted
from gaitpref.feedback import QueryPair, comparison_pairs
from gaitpref.sessions.records import SessionQuery, ShownGait, check_printable, check_storable
from gaitpref.space import MOVES, Feature, Space

COMPARISON_KEYS = {"first": "1", "second": "2", "none": "0"}
#: leaves a gait unrated (after the comparisons, as the digits 1..K rate it)
RATING_SKIP_KEY = "0"
UNDO_KEY = "u"
#: opens "Flag trial N unsafe" (the last trial's) with the focus in its reason; it flags nothing
#: by itself. ``N`` is the one letter besides the note's ``M`` that no suggestion row takes, with
#: any number of features (rows past the fifth have no keys); the terminal's ``x`` is the third
#: feature's "slightly more" here
FLAG_KEY = "n"


def undo_key(space: Space) -> str | None:
    """The undo's shortcut, or None where a suggestion row takes its key (a fourth feature's
    ``Y U I O P``: the suggestion goes first, and the undo is the button's)."""
    rows = SUGGESTION_ROWS[: space.ndim]
    return None if any(UNDO_KEY in row for row in rows) else UNDO_KEY


SUGGESTION_ROWS = ("qwert", "asdfg", "zxcvb", "yuiop", "hjkl;")
_BUTTON_MOVES: tuple[str, ...] = ("+big", "+small", "", "-small", "-big")
_CMP = re.compile(r"^cmp-(\d{1,10})-(\d{1,10})$")
#: a feature is named by an identifier, which may be non-ASCII (``Schrittlänge``, ``μ``)
_SUG = re.compile(r"^sug-(\d{1,10})-([^\W\d]\w{0,99})$")
FORM_FIELDS = ("query_id", "csrf_token", "confirmed", "note")


def fmt_value(value: float) -> str:
    """A feature value as an operator reads it (4 significant digits)."""
    return f"{value:.4g}"


def pretty(name: str) -> str:
    """``step_length`` -> ``step length``."""
    return name.replace("_", " ")


@dataclass(frozen=True)
class FeatureValue:
    name: str
    label: str
    value: float
    text: str
    unit: str


@dataclass(frozen=True)
class GaitView:
    """A grid action as shown: gait id, feature values with units, trial number if any."""

    index: int
    gait_id: str
    trial: int | None
    values: tuple[FeatureValue, ...]
    #: the query's other trials that ran this gait (n > 1 may propose one gait twice)
    also: tuple[int, ...] = ()

    @property
    def text(self) -> str:
        return ", ".join(f"{v.label} {v.text}{' ' + v.unit if v.unit else ''}" for v in self.values)

    @property
    def name(self) -> str:
        """``trial 5 (G12)``, ``trials 4, 5 (G12)`` (:attr:`also`) or ``G12``."""
        if self.also and self.trial:
            return f"trials {', '.join(map(str, (self.trial, *self.also)))} ({self.gait_id})"
        return f"trial {self.trial} ({self.gait_id})" if self.trial else self.gait_id


def executed_once(actions: Sequence[GaitView]) -> list[GaitView]:
    """The query's executed gaits, a gait run in two trials once (naming both: :attr:`also`):
    the session takes one rating and one suggestion per feature for it, and its form fields
    (``rate-<a>``, ``sug-<a>-<feature>``) are one group."""
    out: dict[int, GaitView] = {}
    for gait in actions:
        first = out.get(gait.index)
        if first is None:
            out[gait.index] = gait
        elif gait.trial is not None:
            out[gait.index] = replace(first, also=(*first.also, gait.trial))
    return list(out.values())


def gait_view(
    space: Space, index: int, *, trial: int | None = None, gait_id: str | None = None
) -> GaitView:
    return _view(space, index, space.point(index), trial, gait_id or f"G{int(index)}")


def shown_view(space: Space, shown: ShownGait) -> GaitView:
    """A blind validation gait as its round showed it (not looked up by its row)."""
    point = [shown.values[f.name] for f in space.features]
    return _view(space, shown.action, point, None, shown.gait)


def _view(
    space: Space, index: int, point: Iterable[float], trial: int | None, gait_id: str
) -> GaitView:
    values = tuple(
        FeatureValue(f.name, pretty(f.name), float(x), fmt_value(float(x)), f.unit)
        for f, x in zip(space.features, point, strict=True)
    )
    return GaitView(int(index), gait_id, trial, values)


def move_words(feature: Feature) -> dict[str, str]:
    """Each coactive move in the feature's own words (``+small`` -> ``slightly longer``)."""
    more, less = feature.words
    return {"+big": more, "+small": f"slightly {more}", "-small": f"slightly {less}", "-big": less}


@dataclass(frozen=True)
class Choice:
    """One big button of a group: its form value, label, shortcut and a sentence for review."""

    value: str
    label: str
    key: str
    say: str


@dataclass(frozen=True)
class ComparisonGroup:
    field: str
    first: GaitView
    second: GaitView
    choices: tuple[Choice, ...]


@dataclass(frozen=True)
class SuggestionGroup:
    field: str
    action: GaitView
    position: int  # which executed action of the query (0-based)
    feature: str
    label: str
    choices: tuple[Choice, ...]


@dataclass(frozen=True)
class RatingGroup:
    """The rating buttons of one executed gait: the config's categories, worst first."""

    field: str
    action: GaitView
    position: int
    choices: tuple[Choice, ...]


def rating_groups(categories: Sequence[str], actions: Sequence[GaitView]) -> list[RatingGroup]:
    """One row of buttons per executed gait (none without a rating scale): the categories with
    the digits ``1..K`` as shortcuts, and "no rating" with ``0`` (the default: a trial may go
    unrated)."""
    if not categories:
        return []
    groups = []
    for pos, gait in enumerate(executed_once(actions)):
        choices = tuple(
            Choice(str(k), word, str(k) if k <= 9 else "", f"{gait.name} rated {word!r}")
            for k, word in enumerate(categories, start=1)
        )
        skip = Choice("", "no rating", RATING_SKIP_KEY, "")
        groups.append(RatingGroup(f"rate-{gait.index}", gait, pos, (*choices, skip)))
    return groups


def comparison_groups(
    actions: Sequence[GaitView], buffer: Sequence[GaitView]
) -> list[ComparisonGroup]:
    """The pairs a query asks about (:func:`~gaitpref.feedback.comparison_pairs`, as the
    terminal asks them): each executed gait against the later ones, then against the buffer;
    two trials of one gait are not compared, a pair of gaits is asked once
    (:func:`comparison_notes` says so)."""
    single = len(actions) == 1 and len(buffer) == 1
    members = (*actions, *buffer)
    groups: list[ComparisonGroup] = []
    for pair in _pairs(actions, buffer):
        if not pair.asked:
            continue
        a, b = members[pair.first], members[pair.second]
        first_label = "this one" if single else a.name
        second_label = "previous one" if single else b.name
        choices = (
            Choice(
                "first", first_label, COMPARISON_KEYS["first"], f"{a.name} preferred to {b.name}"
            ),
            Choice(
                "second", second_label, COMPARISON_KEYS["second"], f"{b.name} preferred to {a.name}"
            ),
            Choice(
                "none",
                "no preference",
                COMPARISON_KEYS["none"],
                f"no preference between {a.name} and {b.name}",
            ),
        )
        groups.append(ComparisonGroup(f"cmp-{a.index}-{b.index}", a, b, choices))
    return groups


def comparison_notes(actions: Sequence[GaitView], buffer: Sequence[GaitView]) -> list[str]:
    """Why the page does not ask a pair of the query's trials, in the terminal's words: two
    trials of one gait (nothing to compare), or the same two gaits as a pair asked above."""
    members = (*actions, *buffer)
    notes: list[str] = []
    for pair in _pairs(actions, buffer):
        a, b = members[pair.first], members[pair.second]
        if pair.same_gait:
            notes.append(f"{a.name} and {b.name} are the same gait: nothing to compare")
        elif pair.repeats is not None:
            pa, pb = (members[k] for k in pair.repeats)
            notes.append(
                f"{a.name} against {b.name}: the same gaits as {pa.name} against {pb.name}, "
                "compared once"
            )
    return notes


def _pairs(actions: Sequence[GaitView], buffer: Sequence[GaitView]) -> tuple[QueryPair, ...]:
    return comparison_pairs([g.index for g in actions], [g.index for g in buffer])


def suggestion_groups(space: Space, actions: Sequence[GaitView]) -> list[SuggestionGroup]:
    """One row of five buttons per executed action and feature."""
    groups: list[SuggestionGroup] = []
    for pos, gait in enumerate(executed_once(actions)):
        for row, feature in enumerate(space.features):
            words = move_words(feature)
            keys = SUGGESTION_ROWS[row] if row < len(SUGGESTION_ROWS) else ""
            choices = tuple(
                Choice(
                    move,
                    words[move] if move else "no change",
                    keys[k] if keys else "",
                    f"{pretty(feature.name)}: {words[move]}" if move else "",
                )
                for k, move in enumerate(_BUTTON_MOVES)
            )
            groups.append(
                SuggestionGroup(
                    f"sug-{gait.index}-{feature.name}",
                    gait,
                    pos,
                    feature.name,
                    pretty(feature.name),
                    choices,
                )
            )
    return groups


def suggestion_shortcuts(space: Space) -> list[tuple[Feature, str]]:
    """Each feature with its suggestion row's keys (:data:`SUGGESTION_ROWS`, from "more" to
    "less", as :func:`suggestion_groups` gives its buttons), for the page's list of shortcuts;
    features past the last row have no keys and are left out."""
    return list(zip(space.features, SUGGESTION_ROWS, strict=False))


def read_answer_form(
    form: Mapping[str, str],
) -> tuple[list[tuple[int, int, str]], list[tuple[int, str, str]]]:
    """Comparison and suggestion triples of an answer form (:class:`InputError` names a bad
    field)."""
    comparisons: list[tuple[int, int, str]] = []
    suggestions: list[tuple[int, str, str]] = []
    for name, value in form.items():
        if name in FORM_FIELDS or is_rating_field(name):
            continue
        if m := _CMP.match(name):
            if value not in COMPARISON_KEYS:
                raise InputError(name, f"must be one of first, second, none; got {quoted(value)}")
            comparisons.append((int(m.group(1)), int(m.group(2)), value))
        elif m := _SUG.match(name):
            if value == "":
                continue
            if value not in MOVES:
                said = f"must be one of {', '.join(MOVES)} or empty; got {quoted(value)}"
                raise InputError(name, said)
            suggestions.append((int(m.group(1)), m.group(2), value))
        else:
            raise InputError(name, "unknown field in an answer form")
    return comparisons, suggestions


def free_text(text: str, field: str, what: str) -> str:
    """A note, reason or detail as the session will take it: no control character but a
    newline or a tab, no line separator or bidirectional override, no lone surrogate; else an
    :class:`InputError` naming ``field`` (checked at the confirm step too, not only when it is
    written)."""
    try:
        return check_printable(check_storable(text, what), what)
    except ValueError as exc:
        raise InputError(field, str(exc)) from None


def read_int(form: Mapping[str, str], field: str, *, minimum: int = 1) -> int:
    """An integer form field; :class:`InputError` if it is missing or not an integer."""
    raw = form.get(field)
    if raw is None or raw == "":
        raise InputError(field, "missing")
    if not re.fullmatch(r"\d{1,18}", raw.strip()):
        raise InputError(field, f"must be an integer, got {quoted(raw)}")
    value = int(raw)
    if value < minimum:
        raise InputError(field, f"must be >= {minimum}, got {value}")
    return value


def unanswered(
    space: Space,
    query: SessionQuery,
    comparisons: Sequence[tuple[int, int, str]],
    gait_id: Callable[[int], str | None] | None = None,
) -> list[str]:
    """The confirm step's words for each pair the trial page asks (:func:`comparison_groups`)
    that ``comparisons`` leaves out: a form posted without the page's script saves the pairs
    it answers only (the script asks every one first)."""

    def view(a: int, t: int) -> GaitView:
        return gait_view(space, a, trial=t, gait_id=gait_id(a) if gait_id is not None else None)

    groups = comparison_groups(
        [view(a, t) for a, t in zip(query.actions, query.trials, strict=True)],
        [view(a, t) for a, t in zip(query.buffer, query.buffer_trials, strict=True)],
    )
    given = {frozenset((i, j)) for i, j, _ in comparisons}
    return [
        f"Not answered, not saved: {g.first.name} or {g.second.name}? (Back to answer it)"
        for g in groups
        if frozenset((g.first.index, g.second.index)) not in given
    ]


def answer_summary(
    space: Space,
    query: SessionQuery,
    comparisons: Sequence[tuple[int, int, str]],
    suggestions: Sequence[tuple[int, str, str]],
    gait_id: Callable[[int], str | None] | None = None,
    ratings: Sequence[tuple[int, str]] = (),
) -> list[str]:
    """The answer in words, for the confirm step (``gait_id``: a library's gait ids;
    ``ratings``: ``(action, category)``)."""
    trial_of: dict[int, int] = {}  # a gait's first trial in the query, as the session logs it
    for a, t in zip(query.members, query.member_trials, strict=True):
        trial_of.setdefault(a, t)

    def name(a: int) -> str:
        gait = (gait_id(a) if gait_id is not None else None) or f"G{a}"
        t = trial_of.get(a)
        return f"trial {t} ({gait})" if t is not None else gait

    lines = []
    for i, j, outcome in comparisons:
        if outcome == "none":
            lines.append(f"No preference between {name(i)} and {name(j)}")
        else:
            win, lose = (i, j) if outcome == "first" else (j, i)
            lines.append(f"{name(win)} preferred to {name(lose)}")
    for a, feature, move in suggestions:
        try:
            words = move_words(space.features[space.feature_index(feature)])
        except KeyError:
            words = {}
        lines.append(f"{name(a)}: {pretty(feature)} {words.get(move, move)}")
    if not suggestions:
        lines.append("No suggestions")
    for a, category in ratings:
        lines.append(f"{name(a)} rated {category!r}")
    return lines
