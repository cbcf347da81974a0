"""Issue 12 screen: can the region of avoidance keep the first trials off "very bad" gaits
without a declared-safe start gait?

The ordinal study's setting (``study_ordinal.py``: default strategy, 60 trials, ratings at the
quartiles, its seeds), the ``rated`` arm (no region) against region settings given as
``key=value`` pairs joined by ``,``: ``cautious`` (``[safety] cautious``, default 0.6), ``reach``
(``[safety] reach``, default none) and ``rnoise`` (``[feedback.rating] noise``; default: the
model's noise, 0.01), ``early`` (the default strategy's ``early_scale``, a local challenger
during the first 20 trials; default: off) and ``region=0`` (no region of avoidance: the
strategy alone).  Prints per variant the "very bad" gaits per run over trials 1-60 (and
1-5), the mean objective over trials 1-60, the reduction against ``rated`` and the paired
objective difference.  Results: ``docs/results/ordinal/notes.md``.

    python benchmarks/screen_region_early.py 2d noiseless 40 "cautious=0.8,reach=0.5"
"""

from __future__ import annotations

import dataclasses

import numpy as np
from _usage import positional
from joblib import Parallel, delayed
from study_ordinal import LABELS, Arm, run_one


@dataclasses.dataclass(frozen=True)
class RatedArm(Arm):
    rating_noise: float | None = None
    early_scale: float | None = None

    def text(self, grid: str, start: int | None = None) -> str:
        out = super().text(grid, start)
        if self.early_scale is not None:  # the default strategy's local challenger early
            out += f"\n[cospar.strategy_settings]\nearly_scale = {self.early_scale}\n"
        if self.rating_noise is None:
            return out
        table = f"[feedback.rating]\nlabels = {LABELS}\n"
        return out.replace(table, table + f"noise = {self.rating_noise}\n")


def measure(arm: Arm, grid: str, scenario: str, n: int) -> tuple[np.ndarray, ...]:
    runs = Parallel(n_jobs=2)(delayed(run_one)(arm, grid, scenario, k) for k in range(n))
    worst = np.array([np.sum(np.array(r["categories"]) == 1) for r in runs], dtype=float)
    first = np.array([np.sum(np.array(r["categories"][:5]) == 1) for r in runs], dtype=float)
    objective = np.array([np.mean(r["scores"]) for r in runs])
    return worst, first, objective


def main() -> None:
    args = positional(__doc__, 3)
    grid, scenario, n = args[0], args[1], int(args[2])
    base_w, base_f, base_o = measure(Arm("rated"), grid, scenario, n)
    print(f"rated: worst/run {base_w.mean():.2f} (1-5 {base_f.mean():.2f}) obj {base_o.mean():.3f}")
    for spec in args[3:]:
        kw = dict(kv.split("=") for kv in spec.split(","))
        arm = RatedArm(
            spec, risk=kw.get("region", "1") == "1", cautious=float(kw.get("cautious", 0.6)),
            reach=float(kw["reach"]) if "reach" in kw else None,
            rating_noise=float(kw["rnoise"]) if "rnoise" in kw else None,
            early_scale=float(kw["early"]) if "early" in kw else None,
        )  # fmt: skip
        w, f, o = measure(arm, grid, scenario, n)
        d = o - base_o
        print(
            f"{spec}: worst/run {w.mean():.2f} (1-5 {f.mean():.2f}) obj {o.mean():.3f} "
            f"fewer {1 - w.mean() / base_w.mean():.0%} objective {d.mean():+.3f} "
            f"± {d.std(ddof=1) / np.sqrt(n):.3f}",
            flush=True,
        )


if __name__ == "__main__":
    main()
