#!/usr/bin/env python3
"""The plan against the measured: each piece of a grid run in pieces, its planned seconds against
the CPU seconds its runs took.

    scripts/plan_vs_measured.py --plan PLAN.csv [--cpu CPU.csv[.gz]] --costs COSTS.json --pieces DIR
                                [--share OPT=G ...] [--env ENV] [--out RUNS.csv] [--markdown]

PLAN.csv is `harness plan --runs-csv` of the grid (what grid-in-pieces.sh writes to
DIR/plan.csv); COSTS.json is the calibration the plan used (`harness calibrate`'s cache: seconds of
one forward and one gradient episode of the env). DIR holds the pieces' databases (NAME.sqlite),
read only. A piece whose runs all have `runs.cpu_s` (schema 6: each run's worker-thread CPU over
its sessions, its thread team's and an ext: optimizer's program's included, stored by the harness)
is measured by the sum of those (cpu_from "database"). Other pieces, written by a harness before
schema 6, need CPU.csv: what scripts/piece-cpu-monitor.sh sampled while they ran (each process's utime + stime from /proc, cumulative, so one late sample of
a process counts all of it; cpu_from "monitor").

A running piece's ratio is against its plan pro rata of the episodes it has simulated so far, run by
run: a run done counts its whole plan, a running one the share of its own episodes it has simulated.
A piece counts as measured when its first process started with its first run (within 10 s of the
runs' started_at), and, once done, when its last process was sampled within 40 s of its last
run's finished_at; a process started and ended while the monitor was not running is invisible to
it, and such a piece is listed as unmeasured. Wall seconds are no measure here: pieces side by
side and other work on the machine stretch them 2-4x (and a process stopped with SIGSTOP keeps
its wall clock running).

Each piece's row also gives its plan at its own runs' share of gradient episodes, for an optimizer
whose runs mix forward and gradient episodes (boleap): `--share boleap=0.47` names the registry's
gradient_share at the commit that made the plan; the plan's seconds less its episodes at that share
are the optimizer's own time, and the row's episodes at their calibrated costs are added to it. The
column parts how far the episodes' costs missed from how far the share did. An optimizer whose
episodes are all forward or all gradient ones is planned at its own share already. A sharing
group's later seeds count only the episodes they simulated, gradient ones too, not the prefix they
replayed from its first seed (runs.shared_episodes).
"""
import argparse
import collections
import csv
import datetime
import gzip
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "reports"))
from dsb_report import read_only_db  # noqa: E402


def die(message):
    print(f"plan_vs_measured: {message}", file=sys.stderr)
    sys.exit(2)


def read_csv(path):
    opener = gzip.open if str(path).endswith(".gz") else open
    try:
        with opener(path, "rt", newline="") as f:
            return list(csv.DictReader(f))
    except OSError as e:
        die(f"cannot read {path}: {e.strerror or e}")


def unix(stamp):
    return datetime.datetime.strptime(stamp, "%Y-%m-%dT%H:%M:%SZ").replace(tzinfo=datetime.timezone.utc).timestamp()


def episode_costs(path, env):
    try:
        costs = json.loads(Path(path).read_text())["costs"]
    except (OSError, ValueError, KeyError) as e:
        die(f"cannot read the calibration {path}: {e}")
    found = {k: v for k, v in costs.items() if k.split("|")[0] == env}
    if len(found) != 1:
        die(f"{path} holds {len(found)} calibrations of {env}, need exactly one")
    key, c = next(iter(found.items()))
    return key, float(c["forward_s"]), float(c["gradient_s"])


def pro_rata(planned_s, run, budget):
    """The part of a run's planned seconds that its episodes so far stand for: all of it once done."""
    if run["status"] != "done" and budget:
        shared = run["shared_episodes"] or 0
        own = budget - shared
        return planned_s * (min(1.0, (run["episodes"] - shared) / own) if own > 0 else 1.0)
    return planned_s


def piece_runs(db):
    con = read_only_db.connect(db)
    try:
        # runs.cpu_s from schema 6 on; NULL before
        has_cpu = any(r[1] == "cpu_s" for r in con.execute("PRAGMA table_info(runs)"))
        rows = con.execute(
            "SELECT r.optimizer, r.seed, r.status, r.started_at, r.finished_at, r.episodes, "
            # gradient episodes it simulated: those after the prefix it replayed from its group's lead
            "(SELECT COALESCE(SUM(used_grad), 0) FROM evals e WHERE e.run_id = r.run_id "
            "AND e.episode >= COALESCE(r.shared_episodes, 0)), r.shared_episodes, " +
            ("r.cpu_s " if has_cpu else "NULL ") + "FROM runs r ORDER BY r.seed").fetchall()
    finally:
        con.close()
    return [dict(zip(("optimizer", "seed", "status", "started_at", "finished_at", "episodes", "grad_episodes",
                      "shared_episodes", "cpu_s"), r)) for r in rows]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--plan", required=True)
    ap.add_argument("--cpu", default=None, help="the CPU monitor's log, for pieces without runs.cpu_s")
    ap.add_argument("--costs", required=True)
    ap.add_argument("--pieces", required=True)
    ap.add_argument("--share", action="append", default=[], metavar="OPT=G",
                    help="an optimizer's gradient_share in the registry that made the plan")
    ap.add_argument("--env", default=None, help="the grid's env (default: the plan's only one)")
    ap.add_argument("--out", default=None, help="write one row per piece here (a new file)")
    ap.add_argument("--markdown", action="store_true", help="print the per-family table as Markdown")
    a = ap.parse_args()

    if a.out and Path(a.out).exists():
        die(f"--out {a.out} exists: name a new file")
    shares = {}
    for item in a.share:
        name, _, value = item.partition("=")
        try:
            shares[name] = float(value)
        except ValueError:
            die(f"--share {item}: want OPT=G with G a number")
        if not 0.0 <= shares[name] <= 1.0:
            die(f"--share {item}: G must be from 0 to 1")
    plan = read_csv(a.plan)
    envs = sorted({r["env"] for r in plan})
    env = a.env or (envs[0] if len(envs) == 1 else die(f"the plan has envs {envs}: name one with --env"))
    planned = {(r["optimizer"], int(r["seed"])): float(r["planned_s"]) for r in plan if r["env"] == env}
    budgets = {(r["optimizer"], int(r["seed"])): int(r["budget"]) for r in plan if r["env"] == env}
    if not planned:
        die(f"the plan has no runs of {env}")
    costs_key, forward_s, gradient_s = episode_costs(a.costs, env)

    # piece -> pid -> (process start, first sample time, last sample time, last cpu_s)
    procs = collections.defaultdict(dict)
    for r in (read_csv(a.cpu) if a.cpu else []):
        pid, t, cpu, start = r["pid"], int(r["unix_time"]), float(r["cpu_s"]), int(r["started_at_unix"])
        old = procs[r["piece"]].get(pid)
        procs[r["piece"]][pid] = (start, old[1] if old else t, t, max(cpu, old[3] if old else 0.0))

    pieces_dir = Path(a.pieces)
    if not pieces_dir.is_dir():
        die(f"--pieces {a.pieces}: not a directory")
    rows = []
    for db in sorted(pieces_dir.glob(f"{env}__*.sqlite")):
        piece = db.stem
        runs = piece_runs(db)
        if not runs:
            continue
        optimizer = runs[0]["optimizer"]
        done = all(r["status"] == "done" for r in runs)
        plan_s = sum(planned.get((optimizer, r["seed"]), 0.0) for r in runs)
        simulated = sum(r["episodes"] - (r["shared_episodes"] or 0) for r in runs)
        lead = [r for r in runs if not r["shared_episodes"]]
        # the plan pro rata of each run's own episodes: a run done counts its whole plan, a running
        # one the part of its budget it has simulated past the prefix it replayed (a later seed of a
        # sharing group is planned for its own episodes only)
        plan_so_far = sum(pro_rata(planned.get((optimizer, r["seed"]), 0.0), r, budgets.get((optimizer, r["seed"])))
                          for r in runs)
        grad = sum(r["grad_episodes"] for r in runs)
        p = procs.get(piece, {})
        first_start = min((v[0] for v in p.values()), default=None)
        last_sample = max((v[2] for v in p.values()), default=None)
        started = min(unix(r["started_at"]) for r in runs if r["started_at"])
        finished = max((unix(r["finished_at"]) for r in runs if r["finished_at"]), default=None)
        if all(r["cpu_s"] is not None for r in runs):
            # the harness's own figure: each run's worker-thread CPU over its sessions
            cpu_from, measured, cpu_s = "database", True, sum(r["cpu_s"] for r in runs)
        else:
            measured = bool(p) and abs(first_start - started) <= 10 and (not done or last_sample >= finished - 40)
            cpu_from, cpu_s = ("monitor", sum(v[3] for v in p.values())) if measured else ("", None)
        episodes_s = grad * gradient_s + (simulated - grad) * forward_s
        rows.append({
            "piece": piece, "optimizer": optimizer, "seeds": " ".join(str(r["seed"]) for r in runs),
            "status": "done" if done else "running", "processes": len(p), "measured": int(measured),
            "cpu_from": cpu_from,
            "planned_s": round(plan_s, 2), "cpu_s": "" if cpu_s is None else round(cpu_s, 1),
            # a running piece: against the plan pro rata of the episodes it has simulated
            "ratio": "" if cpu_s is None or plan_so_far <= 0 else round(cpu_s / plan_so_far, 3),
            "episodes": simulated, "grad_episodes": grad,
        })
        r = rows[-1]
        if 0 < grad < simulated and optimizer not in shares:
            die(f"{piece} mixes forward and gradient episodes: give the plan's share with --share {optimizer}=G")
        if optimizer in shares:
            g = shares[optimizer]
            own_s = sum(planned.get((optimizer, x["seed"]), 0.0) - x["episodes"] * (g * gradient_s + (1 - g) * forward_s)
                        for x in lead)
            r["planned_at_own_share_s"] = round(episodes_s + own_s, 2)
            r["ratio_at_own_share"] = "" if cpu_s is None or not done else round(cpu_s / r["planned_at_own_share_s"], 3)
        else:
            r["planned_at_own_share_s"] = r["planned_s"]
            r["ratio_at_own_share"] = r["ratio"]

    if not rows:
        die(f"no piece databases of {env} ({env}__*.sqlite) in {a.pieces}")
    if a.out:
        with open(a.out, "x", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)

    print(f"calibration {costs_key}: forward episode {forward_s:.3f} s, gradient episode {gradient_s:.3f} s")
    for r in rows:
        print(f"  {r['piece']:<38} {r['status']:<7} planned {r['planned_s']:>9.1f} s  cpu "
              f"{r['cpu_s'] if r['cpu_s'] != '' else 'unmeasured':>9}  x{r['ratio'] or '-':<6} "
              f"grad {r['grad_episodes']}/{r['episodes']}  at own share x{r['ratio_at_own_share'] or '-'}")
    if a.markdown:
        print_families(rows)


# the plan's optimizer families (optimizers/registry.cpp's costs.family, `harness plan`'s lines)
FAMILIES = (("forward episodes", ("cmaes", "nlopt-bobyqa", "nlopt-crs2", "nlopt-direct-l", "random")),
            ("gp (episodes + GP time)", ("bo", "boleap")),
            ("gradient episodes", ("gd", "nlopt-lbfgs", "rand-descents")),
            ("rl (episodes + learner)", ("ppo", "sac")))


def print_families(rows):
    print()
    print("| optimizer family | pieces measured (done) | planned s | CPU s | CPU / planned | per piece | "
          "at the runs' own gradient share |")
    print("|---|---|---|---|---|---|---|")
    for family, members in FAMILIES:
        got = [r for r in rows if r["optimizer"] in members and r["status"] == "done" and r["measured"]]
        done = [r for r in rows if r["optimizer"] in members and r["status"] == "done"]
        if not got:
            if done:
                print(f"| {family} | 0 ({len(done)}) | | | | | |")
            continue
        plan_s = sum(r["planned_s"] for r in got)
        cpu_s = sum(r["cpu_s"] for r in got)
        own = sum(r["planned_at_own_share_s"] for r in got)
        ratios = [r["ratio"] for r in got]
        print(f"| {family} ({', '.join(sorted({r['optimizer'] for r in got}))}) | {len(got)} ({len(done)}) | "
              f"{plan_s:,.0f} | {cpu_s:,.0f} | {cpu_s / plan_s:.2f} | {min(ratios):.2f}-{max(ratios):.2f} | "
              f"{cpu_s / own:.2f} |")


if __name__ == "__main__":
    main()
