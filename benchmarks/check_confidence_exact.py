"""Issue 14 diagnosis: is the confidence's under-confidence the Laplace approximation?

The confidence (``loop/stopping.py``) is a Monte Carlo average over joint draws of the Laplace
posterior.  On noiseless subjects it states less than it achieves
(``docs/results/population/fresh/summary.md``), and a sharper probit makes that worse, which
points at the Laplace width rather than the noise level.  This script settles it by stating the
same confidence from draws of the *exact* posterior of the same model and answers:

- on the visited gaits, in the Laplace fit's whitened coordinates ``f_V = L u``, elliptical slice
  sampling (Murray, Adams and MacKay 2010) with the Laplace Gaussian ``N(u_hat, (R R^T)^-1)`` as
  the ellipse and the ratio ``p(y | L u) N(u; 0, I) / N(u; u_hat, (R R^T)^-1)`` as the
  "likelihood", so the chain's stationary law is the exact posterior ``p(u | y)``;
- everywhere else the smooth utility given ``f_V`` is the prior's Gaussian conditional, drawn by
  Matheron's rule from a joint prior draw (as ``Posterior.sample(nugget=False)`` does for the
  Laplace posterior).

Views stated after every answer of cold ``synthetic-2d`` sessions on the fresh clinic's subjects
(the sessions, subjects and seeds of ``check_confidence_jitter.py``):

- ``as_is``: the product's;
- ``exact``: the exact posterior's probability that the product's recommendation (the Laplace
  mean's argmax) is within 5% of the best;
- ``exact_own``: the same with the exact posterior mean's argmax as the recommendation.

All are judged on the subject's objective.  ``--check`` first compares the sampler with
quadrature on a two-gait problem.

    python benchmarks/check_confidence_exact.py --subjects 16 --trials 100 --noise 0 \
        [--every 2] [--out rows.json]
"""

from __future__ import annotations

import argparse

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import cho_solve, solve_triangular
from scipy.special import log_ndtr

from gaitpref.config import load_config
from gaitpref.data import paper_objectives
from gaitpref.loop import CoSpar
from gaitpref.loop.stopping import confidence
from gaitpref.model.posterior import Posterior
from gaitpref.simulate.population import synthetic_population

try:
    from check_confidence_jitter import report, subject_session
    from check_confidence_prior import add_rows_arguments, rows_of, within
except ImportError:  # run as a module
    from benchmarks.check_confidence_jitter import report, subject_session
    from benchmarks.check_confidence_prior import add_rows_arguments, rows_of, within

TOLERANCE = 0.05
Array = NDArray[np.float64]


def slice_sample_visited(
    post: Posterior,
    winners: NDArray[np.intp],
    losers: NDArray[np.intp],
    sigma: Array,
    rng: np.random.Generator,
    *,
    size: int = 300,
    chains: int = 100,
    burn: int = 200,
    thin: int = 10,
    max_shrinks: int = 200,
) -> Array:
    """``size x m`` draws of ``f_V`` from the exact posterior (``chains`` vectorised chains)."""
    fit = post.fit
    assert fit is not None
    visited = fit.visited
    a, b = np.searchsorted(visited, winners), np.searchsorted(visited, losers)
    L, R, u_hat = fit.chol_prior, fit.chol_hessian, fit.whitened_mode
    scale = np.sqrt(2.0) * sigma
    m = visited.shape[0]

    def log_ratio(u: Array) -> Array:
        f = u @ L.T
        loglik = log_ndtr((f[:, a] - f[:, b]) / scale).sum(axis=1)
        d = (u - u_hat) @ R  # (u - u_hat)^T R R^T (u - u_hat) = |R^T (u - u_hat)|^2
        out: Array = loglik - 0.5 * np.einsum("ij,ij->i", u, u) + 0.5 * np.einsum("ij,ij->i", d, d)
        return out

    def reference(count: int) -> Array:  # N(0, (R R^T)^-1): R^-T z
        z = rng.standard_normal((m, count))
        out: Array = solve_triangular(R, z, lower=True, trans="T", check_finite=False).T
        return out

    u = u_hat + reference(chains)
    current = log_ratio(u)
    kept: list[Array] = []
    steps = burn + thin * -(-size // chains)
    for step in range(steps):
        nu = reference(chains)
        level = current + np.log(rng.uniform(size=chains))
        theta = rng.uniform(0.0, 2.0 * np.pi, size=chains)
        lo, hi = theta - 2.0 * np.pi, theta.copy()
        todo = np.ones(chains, dtype=bool)
        for _ in range(max_shrinks):
            idx = np.flatnonzero(todo)
            if idx.size == 0:
                break
            t = theta[idx, None]
            proposal = u_hat + (u[idx] - u_hat) * np.cos(t) + nu[idx] * np.sin(t)
            value = log_ratio(proposal)
            ok = value > level[idx]
            u[idx[ok]], current[idx[ok]] = proposal[ok], value[ok]
            todo[idx[ok]] = False
            bad = idx[~ok]
            neg = theta[bad] < 0
            lo[bad[neg]] = theta[bad[neg]]
            hi[bad[~neg]] = theta[bad[~neg]]
            theta[bad] = rng.uniform(lo[bad], hi[bad])
        else:
            raise RuntimeError(f"elliptical slice sampling did not accept in {max_shrinks} shrinks")
        if step >= burn and (step - burn) % thin == thin - 1:
            kept.append(u @ L.T)
    out: Array = np.concatenate(kept)[:size]
    return out


def smooth_given_visited(post: Posterior, f_visited: Array, rng: np.random.Generator) -> Array:
    """Draws of the smooth utility over every gait given ``f_V`` (rows), by Matheron's rule."""
    fit = post.fit
    assert fit is not None
    visited, kernel = fit.visited, post.kernel
    f0, e0 = post.engine.prior_parts(rng, f_visited.shape[0])
    coef = cho_solve((fit.chol_prior, True), (f_visited - f0[:, visited]).T, check_finite=False)
    cross = kernel.cross(post.space, visited)  # A x m, the jitter where the row is the column
    cross[visited, np.arange(visited.shape[0])] -= kernel.jitter
    g = f0 if e0 is None else f0 - e0
    out: Array = g + (cross @ coef).T
    return out


def answers_of(loop: CoSpar) -> tuple[NDArray[np.intp], NDArray[np.intp], Array]:
    """The loop's preferences in force: winners, losers and each one's probit noise."""
    prefs = loop.preferences
    winners = np.array([p.winner for p in prefs], dtype=np.intp)
    losers = np.array([p.loser for p in prefs], dtype=np.intp)
    sigma = np.array([loop.gp.noise if p.noise is None else p.noise for p in prefs])
    return winners, losers, sigma


def stated(samples: Array, rec: int, tolerance: float = TOLERANCE) -> float:
    best, worst = samples.max(axis=1), samples.min(axis=1)
    return float(np.mean(best - samples[:, rec] <= tolerance * (best - worst)))


def check(rng: np.random.Generator) -> None:
    """The sampler against quadrature: two gaits, three answers, a small probit noise."""
    config = load_config("synthetic-2d")
    gp = config.make_loop(seed=np.random.default_rng(0)).gp
    winners, losers = np.array([0, 0, 0]), np.array([5, 5, 5])
    sigma = np.full(3, 0.1 * gp.noise)
    post = gp.posterior(winners, losers, sigma)
    draws = slice_sample_visited(post, winners, losers, sigma, rng, size=20000, chains=200)
    assert post.fit is not None
    k = post.fit.chol_prior @ post.fit.chol_prior.T
    sd = np.sqrt(np.diag(k))
    x = np.linspace(-6 * sd[0], 6 * sd[0], 801)
    y = np.linspace(-6 * sd[1], 6 * sd[1], 801)
    X, Y = np.meshgrid(x, y, indexing="ij")
    pts = np.stack([X.ravel(), Y.ravel()], axis=1)
    logp = -0.5 * np.einsum("ij,jk,ik->i", pts, np.linalg.inv(k), pts)
    diff = pts[:, 0] - pts[:, 1]
    for w, s in zip(winners, sigma, strict=True):
        sign = 1.0 if w == 0 else -1.0
        logp += log_ndtr(sign * diff / (np.sqrt(2.0) * s))
    p = np.exp(logp - logp.max())
    p /= p.sum()
    mean = p @ pts
    sd_q = np.sqrt(p @ (pts - mean) ** 2)
    print("quadrature mean", mean, "sd", sd_q)
    print("sampler    mean", draws.mean(axis=0), "sd", draws.std(axis=0))
    laplace_sd = np.sqrt(np.diag(post.covariance_at(post.visited)))
    print("laplace    mode", post.fit.mode, "sd", laplace_sd)


def run(
    subjects: int, trials: int, samples: int, noise: float, every: int, first: int = 0
) -> list[dict[str, object]]:
    config = load_config("synthetic-2d")
    utilities = synthetic_population(paper_objectives(), 0.5, first + subjects, shared=99, first=25)
    rows: list[dict[str, object]] = []
    for s in range(first, first + subjects):
        loop, user, truth = subject_session(config, utilities[s], s, noise)
        for t in range(trials):
            query = loop.ask()
            loop.tell(query, user.answer(query))
            if (t + 1) % every:
                continue
            post = loop.posterior
            winners, losers, sigma = answers_of(loop)
            sure = confidence(
                post, np.random.default_rng([s, t, 3]), tolerance=TOLERANCE, samples=samples
            )
            rng = np.random.default_rng([s, t, 4])
            if post.fit is None:  # no comparison yet: the prior is exact
                g = post.sample(rng, samples, nugget=False)
            else:
                f_v = slice_sample_visited(post, winners, losers, sigma, rng, size=samples)
                g = smooth_given_visited(post, f_v, rng)
            own = int(np.argmax(g.mean(axis=0)))
            rows.append(
                {
                    "s": s,
                    "t": t,
                    "as_is": sure.probability,
                    "as_is_ok": within(truth, sure.recommended, TOLERANCE),
                    "exact": stated(g, sure.recommended),
                    "exact_ok": within(truth, sure.recommended, TOLERANCE),
                    "exact_own": stated(g, own),
                    "exact_own_ok": within(truth, own, TOLERANCE),
                }
            )
        print(f"subject {s} done", flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--subjects", type=int, default=16)
    parser.add_argument("--trials", type=int, default=100)
    parser.add_argument("--samples", type=int, default=300)
    parser.add_argument("--first", type=int, default=0, help="the first subject's index")
    parser.add_argument("--every", type=int, default=1, help="state it after every k-th answer")
    parser.add_argument(
        "--noise", type=float, default=0.0, help="the subjects' noise, times the model's (0: none)"
    )
    parser.add_argument("--check", action="store_true", help="check the sampler by quadrature")
    add_rows_arguments(parser)
    args = parser.parse_args()
    if args.check:
        check(np.random.default_rng(0))
        return
    rows = rows_of(
        args,
        lambda: run(args.subjects, args.trials, args.samples, args.noise, args.every, args.first),
    )
    print(report(rows, ("as_is", "exact", "exact_own")))


if __name__ == "__main__":
    main()
