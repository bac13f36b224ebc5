#!/usr/bin/env python3
"""Fits the GP cost model's constants to measured runs (scripts/gp-cost-fit.sh).

    /usr/bin/python3 scripts/gp_cost_fit.py DB OUT.csv

DB holds bo and boleap runs at 200 and 1,000 episodes (seed 0). For each (env, optimizer): own(B) =
the run's wall seconds less its episodes' (evals.wall_s), and growth = own(1000) - own(200), the
part a plan adds to a 200-episode probe. The model (optimizers/bo/gp_cost.cpp, its default
configs) says growth = a S3 + b S2D + c SA, where S3 and S2D sum evaluations x n^3 and evaluations
x n^2 d over the fits between 200 and 1,000 episodes, and SA (bo only: boleap proposes once per
leap) sums LCB evaluations x n (n + d) over those episodes' acquisitions; a, b and c
(kBoSecondsPerN3, kBoSecondsPerN2D, kBoSecondsPerLcbTerm) minimise the squared log ratio of model
to measurement over the runs. Prints the constants and writes each run's numbers to OUT.csv (a new
file only: an existing OUT.csv exits 2).
"""
import csv
import json
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "reports"))
from dsb_report import read_only_db  # noqa: E402

try:
    from scipy.optimize import least_squares
except ImportError as e:  # pragma: no cover
    sys.stderr.write(f"gp_cost_fit: {sys.executable} cannot import {e.name}; use /usr/bin/python3\n")
    sys.exit(2)

# the defaults the plan's model uses (optimizers/bo/bo.hpp BoConfig, optimizers/boleap.hpp,
# optimizers/bo/gp_cost.hpp)
REFIT_EVERY_UNTIL = 50
REFIT_GROWTH = 0.1
EPISODES_PER_LEAP = 100
BO_EVALUATIONS_PER_FIT = 80.0
BOLEAP_EVALUATIONS_BASE = 70.0
BOLEAP_EVALUATIONS_PER_POINT = 0.17
LCB_EVALUATIONS = 512 + 5 * 60  # LcbConfig: raw samples + restarts x L-BFGS evaluations


def initial_points(dim):
    return min(max(dim + 1, 5), 20)


def bo_fits(dim, budget):
    """(evaluations, n) of each fit of bo's schedule (gp_cost.cpp for_each_fit)"""
    first, last, fits = min(initial_points(dim), budget), 0, []
    for n in range(first, budget + 1):
        if n == first or n <= REFIT_EVERY_UNTIL or n >= math.ceil((1.0 + REFIT_GROWTH) * last):
            fits.append((BO_EVALUATIONS_PER_FIT, n))
            last = n
    return fits


def boleap_fits(dim, budget):
    """(evaluations, n) of each fit of boleap's schedule (gp_cost.cpp for_each_leap_fit)"""
    first, fits = min(initial_points(dim), budget), []
    n = first
    while n == first or n < budget:
        fits.append((BOLEAP_EVALUATIONS_BASE + BOLEAP_EVALUATIONS_PER_POINT * n, n))
        n += EPISODES_PER_LEAP
    return fits


def sums(optimizer, dim, budget):
    """(sum of evaluations n^3, sum of evaluations n^2 d) over a run's fits, and the sum of LCB
    evaluations n (n + d) over its acquisitions (gp_cost.cpp bo_acquisition_seconds)"""
    fits = (bo_fits if optimizer == "bo" else boleap_fits)(dim, budget)
    acquisitions = 0.0
    if optimizer == "bo":
        acquisitions = LCB_EVALUATIONS * sum(n * (n + dim) for n in range(min(initial_points(dim), budget), budget))
    return sum(e * n**3 for e, n in fits), sum(e * n * n * dim for e, n in fits), acquisitions


def model(row, a, b, c):
    """the model's seconds for a row's sums (s3, s2d, sa) at constants a, b, c"""
    return a * row["s3"] + b * row["s2d"] + c * row["sa"]


def fit_constants(rows):
    """(a, b, c) minimising the squared log ratios model / growth_s over the rows"""
    # parameters in log so that they stay positive
    def residuals(p):
        return [math.log(model(r, *map(math.exp, p)) / r["growth_s"]) for r in rows]

    fit = least_squares(residuals, [math.log(1e-10), math.log(1e-9), math.log(1e-10)], x_scale=1.0,
                        xtol=1e-12, ftol=1e-12)
    return tuple(map(math.exp, fit.x))


def main():
    if len(sys.argv) != 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    db, out = sys.argv[1:]
    if not os.path.exists(db):
        sys.stderr.write(f"gp_cost_fit: no database '{db}'\n")
        sys.exit(2)
    if os.path.exists(out):
        sys.stderr.write(f"gp_cost_fit: '{out}' exists; it writes a new file only\n")
        sys.exit(2)
    con = read_only_db.connect(db)
    own, dims, fits = {}, {}, {}
    for env, opt, budget, wall, best_x, sim, diagnostics in con.execute(
            "SELECT r.env, r.optimizer, r.budget, r.wall_s, r.best_x, (SELECT SUM(wall_s) FROM evals e "
            "WHERE e.run_id = r.run_id), r.diagnostics FROM runs r WHERE r.status = 'done' AND r.seed = 0 "
            "AND r.optimizer IN ('bo', 'boleap') AND r.budget IN (200, 1000)"):
        own[env, opt, budget] = wall - sim
        dims[env] = len(json.loads(best_x))
        # the fits the run made (its diagnostics), beside the model's schedule
        gp = json.loads(diagnostics)["optimizer"]
        fits[env, opt, budget] = (gp if opt == "bo" else gp["gp"])["gp_fits"]
    rows = []
    for (env, opt, budget) in sorted(own):
        if budget != 1000 or (env, opt, 200) not in own:
            continue
        s3_hi, s2_hi, sa_hi = sums(opt, dims[env], 1000)
        s3_lo, s2_lo, sa_lo = sums(opt, dims[env], 200)
        model_fits = len((bo_fits if opt == "bo" else boleap_fits)(dims[env], 1000))
        rows.append(dict(env=env, optimizer=opt, dim=dims[env], fits=fits[env, opt, 1000], model_fits=model_fits,
                         own_200_s=own[env, opt, 200],
                         own_1000_s=own[env, opt, 1000], growth_s=own[env, opt, 1000] - own[env, opt, 200],
                         s3=s3_hi - s3_lo, s2d=s2_hi - s2_lo, sa=sa_hi - sa_lo))
    if len(rows) < 3:
        sys.stderr.write(f"gp_cost_fit: {len(rows)} (env, optimizer) pairs with both budgets in '{db}'; need 3\n")
        sys.exit(2)
    a, b, c = fit_constants(rows)
    with open(out + ".tmp", "x", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["env", "optimizer", "dim", "fits", "model_fits", "own_200_s", "own_1000_s", "growth_s", "model_s",
                    "ratio"])
        for r in rows:
            m = model(r, a, b, c)
            w.writerow([r["env"], r["optimizer"], r["dim"], r["fits"], r["model_fits"], f"{r['own_200_s']:.4g}", f"{r['own_1000_s']:.4g}",
                        f"{r['growth_s']:.4g}", f"{m:.4g}", f"{m / r['growth_s']:.3f}"])
    os.replace(out + ".tmp", out)
    ratios = [model(r, a, b, c) / r["growth_s"] for r in rows]
    print(f"kBoSecondsPerN3 = {a:.3g}; kBoSecondsPerN2D = {b:.3g}; kBoSecondsPerLcbTerm = {c:.3g} "
          f"(model / measured {min(ratios):.2f}-{max(ratios):.2f} over {len(rows)} runs) -> {out}")


if __name__ == "__main__":
    main()
