#!/usr/bin/env python3
"""scipy's differential evolution as a diffsim-bench external optimizer (docs/ext-protocol.md):

    harness --env sphere-10,cartpole1 --optimizer ext:de,cmaes \
            --ext de='/usr/bin/python3 examples/ext/scipy_de.py' --seeds 2 --budget 60

scipy.optimize.differential_evolution, vectorized: each generation's population is one batch ask
in the protocol's binary form (Session.ask_array; the harness may evaluate it on several threads,
--threads). Population: 15 x dim (scipy's
default) but at most max(5, budget / 20), so that a run sees about 20 generations; the first
population uniform in the box; no polishing (scipy's L-BFGS-B polish would spend episodes on
finite differences). When DE converges it starts again with a new population, until the budget
ends. numpy Generator seeded with the run's seed from the hello. Failed episodes count as inf.
"""
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import scipy  # noqa: E402
from scipy.optimize import differential_evolution  # noqa: E402

import dsb_protocol as dsb  # noqa: E402


def optimize(s):
    rng = np.random.default_rng(s.seed)
    lower, upper = np.array(s.lower), np.array(s.upper)
    bounds = list(zip(s.lower, s.upper))
    population = int(min(15 * s.dim, max(5, s.budget // 20)))

    def losses(xs):  # xs: dim x population (vectorized); sent as binary doubles (exact, cheap)
        return s.evaluate_array(xs.T)

    while True:  # restarts until BudgetEnd
        init = rng.uniform(lower, upper, size=(population, s.dim))
        differential_evolution(losses, bounds, init=init, seed=rng, vectorized=True, updating="deferred",
                               polish=False, maxiter=100000)


if __name__ == "__main__":
    dsb.main("scipy-de", "1 (scipy %s, numpy %s)" % (scipy.__version__, np.__version__), optimize)
