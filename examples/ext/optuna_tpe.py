#!/usr/bin/env python3
"""Optuna's TPE sampler as a diffsim-bench external optimizer (docs/ext-protocol.md):

    harness --env sphere-10,bounce --optimizer ext:tpe,cmaes \
            --ext tpe='/usr/bin/python3 examples/ext/optuna_tpe.py' --seeds 2 --budget 60

One in-memory study per run, one trial per episode (ask, evaluate, tell), TPESampler with
Optuna's defaults, seeded with the run's seed (mod 2**32: Optuna seeds numpy's RandomState).
A failed episode is told as a failed trial. TPE's time per trial grows with the dimension and the
trials so far: about 25 ms at D = 10 and 0.5 s at D = 200 after 60 trials on our CI machine, so
it suits the low-dimensional envs. Debian 12: python3-optuna (scripts/install-deps.sh).
"""
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import math  # noqa: E402

import optuna  # noqa: E402
from optuna.distributions import FloatDistribution  # noqa: E402
from optuna.trial import TrialState  # noqa: E402

import dsb_protocol as dsb  # noqa: E402


def optimize(s):
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(sampler=optuna.samplers.TPESampler(seed=s.seed % 2**32))
    names = ["x%04d" % i for i in range(s.dim)]
    space = {n: FloatDistribution(lo, hi) for n, lo, hi in zip(names, s.lower, s.upper)}
    while True:  # until BudgetEnd
        trial = study.ask(space)
        loss = s.evaluate([trial.params[n] for n in names])
        if math.isfinite(loss):
            study.tell(trial, loss)
        else:
            study.tell(trial, state=TrialState.FAIL)


if __name__ == "__main__":
    dsb.main("optuna-tpe", "1 (optuna %s)" % optuna.__version__, optimize)
