"""Issue 13: two line-path arms of ``study_continuous.py`` paired by seed, cell by cell.

Each argument is a ``results.json`` that ``study_continuous.py --out DIR`` wrote (same seeds,
so the same objective draws, loop and subject seeds).  Prints a markdown table of the best@60
fraction (random selection 0, the optimum 1) of both arms, mean ± standard error over the
seeds they share, the paired difference (second minus first), and the same over every cell
without coactive feedback in 8-D and 12-D; and each arm's share of trials 2-60 that ran the
trial before's point again (a repeat, read from the executed objective values: two equal
values in a row are one point run twice).

    python benchmarks/compare_line_arms.py FIRST/results.json SECOND/results.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np


def _fraction60(run: dict[str, Any]) -> float:
    best = float(run["best_at"]["60"])
    return (best - run["random_mean"]) / (run["optimum"] - run["random_mean"])


def _repeats60(run: dict[str, Any]) -> float:
    curve = np.asarray(run["curve"][:60])
    return float(np.mean(curve[1:] == curve[:-1]))


Cells = dict[tuple[Any, ...], dict[int, tuple[float, float]]]


def _by_cell(path: Path) -> Cells:
    out: Cells = {}
    for r in json.loads(path.read_text())["runs"]:
        if r["path"] != "line":
            continue
        key = (r["objective"], r["d"], r["coactive"], r["noise"])
        out.setdefault(key, {})[r["seed"]] = (_fraction60(r), _repeats60(r))
    return out


def _mse(a: np.ndarray) -> str:
    return f"{a.mean():.3f} ± {a.std(ddof=1) / np.sqrt(a.size):.3f}"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("first", type=Path)
    parser.add_argument("second", type=Path)
    args = parser.parse_args()
    first, second = _by_cell(args.first), _by_cell(args.second)
    print(
        "| objective | d | coactive | noise | seeds | first | second | second - first "
        "| repeats 2-60: first / second |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    pooled: list[np.ndarray] = []
    for key in sorted(set(first) & set(second)):
        seeds = sorted(set(first[key]) & set(second[key]))
        if len(seeds) < 2:
            continue
        a, ra = np.array([first[key][s] for s in seeds]).T
        b, rb = np.array([second[key][s] for s in seeds]).T
        objective, d, co, noise = key
        print(
            f"| {objective} | {d} | {'yes' if co else 'no'} | {noise} | {len(seeds)} | "
            f"{_mse(a)} | {_mse(b)} | {_mse(b - a)} | {ra.mean():.2f} / {rb.mean():.2f} |"
        )
        if not co and d in (8, 12):
            pooled.append(b - a)
    if pooled:
        per_seed = np.mean(np.array(pooled), axis=0)  # the cells' mean difference, per seed
        print(f"\nCells without coactive feedback, 8-D and 12-D, per seed: {_mse(per_seed)}")


if __name__ == "__main__":
    main()
