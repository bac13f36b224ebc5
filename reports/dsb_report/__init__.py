"""Helpers of reports/make_report.py: the diffsim-bench comparison report.

Modules, one purpose each:
  data        read a harness database (read-only) into runs, panels and best-so-far matrices
  read_only_db  open a database to read it, leaving its folder as found (standard library only)
  grid        the expected (env, optimizer, seed, budget) grid: missing, failed and running runs
  stats       per-cell statistics, Student-t CIs, Mann-Whitney + Holm, A12, ranks, ECDF of targets
  claims      the paper's qualitative claims (paper_claims.csv) tested over the database, verdicts
  claim_runs  what an unsettled claim lacks (env, runs missing or not done) and its command
  metric_counts  per optimizer, the seeds over a metric claim's threshold (the cube over the rim)
  registry    `harness list`: which envs exist, which optimizers --all runs on each
  style       palette (one fixed color per optimizer), fonts, the log-scale rule
  charts      what a chart declaration holds (file, section, alt text, caption), drawing a section's charts
  plots       the charts: curves, finals, ranks, ECDF, each a function and its declaration (CHARTS)
  landscape   heat maps with gradient arrows from `harness landscape` CSVs
  tables      CSV and Markdown writers
  html        index.html
"""
