#!/usr/bin/env python3
"""scipy's L-BFGS-B as a diffsim-bench external optimizer (docs/ext-protocol.md):

    harness --env sphere-10,cartpole1 --optimizer ext:lbfgsb,gd \
            --ext lbfgsb='/usr/bin/python3 examples/ext/scipy_lbfgsb.py' --seeds 2 --budget 60

From the box centre, then from uniform random starts (numpy Generator seeded with the run's
seed from the hello) until the budget ends. With the env's gradient (one episode per call, asked
with grad) when the hello says gradient: true; otherwise scipy's own finite differences, each an
episode. A failed episode (loss inf) is given to scipy as 1e300 with a zero gradient.
"""
import os

# one thread in numpy's BLAS: the harness runs several runs at once, and results stay the same
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import math  # noqa: E402

import numpy as np  # noqa: E402
import scipy  # noqa: E402
from scipy.optimize import minimize  # noqa: E402

import dsb_protocol as dsb  # noqa: E402

PENALTY = 1e300


def optimize(s):
    rng = np.random.default_rng(s.seed)
    lower, upper = np.array(s.lower), np.array(s.upper)
    bounds = list(zip(s.lower, s.upper))

    def loss_and_grad(x):
        loss, grad = s.evaluate_with_grad(np.clip(x, lower, upper).tolist())
        if not math.isfinite(loss):
            return PENALTY, np.zeros(s.dim)
        return loss, np.array(grad)

    def loss_only(x):
        loss = s.evaluate(np.clip(x, lower, upper).tolist())
        return loss if math.isfinite(loss) else PENALTY

    x0 = (lower + upper) / 2.0
    while True:  # restarts until BudgetEnd
        if s.gradient:
            minimize(loss_and_grad, x0, jac=True, method="L-BFGS-B", bounds=bounds,
                     options={"maxfun": s.remaining + 1})
        else:
            minimize(loss_only, x0, method="L-BFGS-B", bounds=bounds,
                     options={"maxfun": s.remaining + 1})
        x0 = rng.uniform(lower, upper)


if __name__ == "__main__":
    dsb.main("scipy-lbfgsb", "1 (scipy %s, numpy %s)" % (scipy.__version__, np.__version__), optimize)
