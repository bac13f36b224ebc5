"""How to read the report's tables and sections: the texts in index.html and summary.md, and the
y-axis sentences ({scale}) of the per-env charts. A chart's own caption is in its declaration
(plots.CHARTS)."""

SCALE_LINEAR = "Linear y axis."
SCALE_LOG = "Log y axis: the losses are positive and span more than two decades."
SCALE_SHIFTED = ("Log y axis of the loss minus f* (= {fstar}, the best loss any optimizer found on "
                 "this env) plus a tiny offset δ = {delta} so that the best run stays visible: some "
                 "losses are zero or negative, which a log axis cannot show directly.")

SCALE_REGRET = ("Log y axis of the regret f − f*: the loss minus the env's known optimum f* = {fstar} "
                "(data/known_optima.csv, from envs/synthetic), not the best loss found, so 1e-6 means "
                "within 1e-6 of the true minimum; a regret at or below {floor} (a loss at f* to "
                "rounding) is drawn at {floor}.")

OVERVIEW = ("Each cell: the optimizer's median final best loss over seeds, normalised per env as "
            "(median − lowest median) / (highest median − lowest median): 0 = the env's winner, "
            "1 = the worst optimizer there (a median of +∞, no finite loss, counts 1). Where an "
            "env's medians are positive and the highest is more than 100 times the lowest (log "
            "colour scale, under the env's name), the same on their logarithms, (log median − log "
            "lowest) / (log highest − log lowest), so that medians orders of magnitude apart get "
            "different colours. ★ best: the "
            "lowest median; ≈ best: a one-sided Mann-Whitney U test (worse than the winner?), "
            "Holm-corrected over the env's comparisons, cannot tell it apart at α = 0.05 (a tie); "
            "too few seeds: even perfectly separated samples of these seed counts could not reach "
            "α, so the test says nothing; no mark: worse than the winner. Colour: green (0) to "
            "red (1). The raw medians are in each env's section and in summary.md.")

FAILURES = ("Failed episodes: the episodes of the analysed 'done' runs whose simulation blew up "
            "(loss NaN, stored as NULL; such an episode never becomes the best); failed runs: runs "
            "with status 'failed' (excluded from every statistic, listed under Failed runs). "
            "Cells: failed episodes / failed runs; — = no run of that pair.")

ONE_RUN = ("An optimizer whose seeds are one run on an env (each of its runs recorded seed-free "
           "over all its episodes: it never drew from its random generator, so every seed gives the "
           "same run, as gd from the box centre does) is one sample there, not one per seed: the "
           "other side of a comparison is tested against its single value by the exact one-sided "
           "sign test (scipy.stats.binomtest: k of the n seeds that differ from it on the tested "
           "side, P(Bin(n, 1/2) >= k); valid without assuming a symmetric distribution, which the "
           "one-sample Wilcoxon signed-rank test would need; with 5 seeds its smallest p is 1/32), "
           "and two such optimizers by their order, which is certain (p 0 or 1); Holm as for the rest.")

CLAIMS = ("Each row is a qualitative claim of Antonova et al. (CoRL 2022) tested on the final best "
          "losses over seeds (the env's largest budget; no finite loss = +inf): one-sided "
          "Mann-Whitney U tests (two-sided for 'no difference' claims), Holm-corrected over the "
          "claim's comparisons, α = 0.05; p is the deciding corrected p (the largest for a claim of "
          "differences, the smallest for a claim of none), A12 the probability that a run of the "
          "first optimizer ends lower than one of the other (0.5 = no effect). 'not enough data': "
          "every run the claim needs is done, but even perfectly separated samples could not "
          "reach α after Holm (comparisons × 1/C(nA+nB, nA), doubled if two-sided, ≥ α: one "
          "comparison needs 4 seeds a side; against an optimizer whose seeds are one run the sign "
          "test's 2^−n: 5 seeds); 'not testable': the database does not record what "
          "the paper judged. " + ONE_RUN)

CLAIMS_SETTLE = ("A claim the database cannot settle yet says what it lacks: 'env missing' (the "
                 "harness has no such env, per `harness list`), 'runs missing: k of n done' (the "
                 "env exists; of the n runs the claim needs, {seeds} seeds of each optimizer it names at "
                 "the env's largest budget, only k are in the database as done) or 'runs "
                 "incomplete: k of n done' (some of those runs are running, were stopped part-way "
                 "or failed), and names the command that makes its runs: the claims grid of the "
                 "harness restricted to that env.")

METRIC_COUNTS = ("For each env of a claim on its second metric (fluid: the cube's height, lifted over the "
                 "tank's rim at 0.2 m), every optimizer's runs at the env's largest budget whose "
                 "metric at the episode of their final best loss reaches the claim's threshold, of "
                 "its runs there; the claim itself judges only the optimizers it names.")

SIGNIFICANCE = ("For each env, the best optimizer is the one with the lowest median final loss. Every "
                "other optimizer's final best losses over seeds are compared with the best one's by a "
                "one-sided Mann-Whitney U test, whether they tend to be higher (scipy.stats."
                "mannwhitneyu: exact for small samples without ties, normal approximation "
                "otherwise; one-sided because the best is the lowest median by construction, and "
                "two-sided tests could not separate ten optimizers at 5 seeds after Holm); the "
                "p-values of one env are "
                "Holm-corrected over its comparisons, and an optimizer is indistinguishable from the "
                "best when the corrected p is ≥ 0.05. {minp}")

GRADIENT_QUALITY = (
    "Where the analytic gradients can be trusted: `harness gradcheck` at seeded random points of "
    "each env ({settings}; scripts/gradient-quality.sh). 'agree': the fraction of points where "
    "every coordinate of the analytic gradient g agrees with the central difference fd of the "
    "loss at step h in normalized units (|g_i − fd_i| / (|fd_i| + 10^−3 max_j |fd_j|) ≤ the "
    "tolerance). 'exactly zero': the fraction of points where every component of g is 0.0 (flat "
    "regions, e.g. pinball paddles the ball never touches). |grad|: the Euclidean norm of g in "
    "normalized units over the points (min, median, max). 'opposed at large step': among the "
    "points with a nonzero finite gradient, the fraction where the loss falls along +g over a "
    "step H: with u = g/|g|, (f(x + H u) − f(x − H u)) / 2H < 0 (the window shifted along u to "
    "stay in the box), i.e. the gradient points the wrong way at the scale an optimizer steps; "
    "the last column is the median of that large-step slope divided by |g| (1: the gradient "
    "predicts the loss over the step; near 0: a plateau or a gradient that overstates the slope; "
    "negative: opposed). The particle envs (fluid, plb-NAME) are surveyed at their 5-env-step "
    "variants (named in the env column); all others at their full horizon. Green: every point "
    "agrees and none is opposed; red: fewer than half agree or a quarter or more are opposed.")

LANDSCAPE = ("Colors: the loss on a 2-D slice of the normalized box through dimensions i and j "
             "(the other coordinates as `harness landscape` fixed them). Arrows: the descent "
             "direction (minus the gradient) on at most 20 × 20 grid points, drawn with unit "
             "length; arrow color: log10 of the gradient magnitude, so flat regions and cliffs "
             "stand out. Red crosses (slices made with `--check-step`): points where the "
             "gradient disagrees with central differences of the loss.")

MISSING = ("Expected grid: every (env, optimizer) pair with at least one run in the database, times "
           "seed indices 0..{max_seed}, times the budgets present for that env. Every expected run "
           "without a 'done' run is listed here; reason 'failed' or 'running' means such a run "
           "exists (see below), 'absent' means none was ever stored.")

GALLERY = ("The loss on 2-D slices of every env given to the report (--landscapes DIR; "
           "scripts/landscape-gallery.sh DIR makes one for every env of `harness list`, on the "
           "seed's Figures 8-15 dims where it gives them, else the first two dims, the particle "
           "envs at their 5-env-step variants), side by side per env under that env's row of the "
           "gradient quality survey. " + LANDSCAPE)

STALE_LEFT_OUT = ("Runs made by other results versions than the harness's (docs/database.md, \"Results "
                  "versions\"): another code made them, so they are left out of every table, figure, "
                  "test and claim, and count as not done (a grid of this harness runs them anew). "
                  "--include-stale shows them, each under its own name.")

STALE_SHOWN = ("Runs made by other results versions than the harness's (docs/database.md, \"Results "
               "versions\"), shown as asked (--include-stale): each (optimizer, stored versions) is an "
               "optimizer of its own, named as in the IOH export, never pooled with the current runs "
               "of its optimizer; the claims judge current runs only.")
