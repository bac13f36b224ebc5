#!/usr/bin/env python3
"""scripts/boleap_study_choice.py: the rule that picks BO-Leap's defaults from the study's table,
on small tables whose answer is worked out by hand (ctest boleap_study_choice).

    python3 tests/test_boleap_study_choice.py SOURCE_DIR
"""
import csv
import io
import os
import subprocess
import sys
import tempfile
import unittest

SOURCE = sys.argv.pop(1) if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
sys.path.insert(0, os.path.join(SOURCE, "scripts"))
import boleap_study_choice as choice  # noqa: E402

ENVS = ("cartpole1", "cartpole3", "rastrigin-10")


def table(medians, extra=()):
    """{variant: (m1, m2, m3)} -> the table's rows (boleap), plus `extra` rows as given"""
    rows = [{"env": e, "optimizer": "boleap", "variant": v, "median": repr(m)}
            for v, ms in medians.items() for e, m in zip(ENVS, ms)]
    return rows + list(extra)


class Rule(unittest.TestCase):
    def test_the_best_mean_rank_wins(self):
        # ranks: default 2,2,2; sigma0=0.1 1,3,1 (mean 1.67); J=30 3,1,3 (2.33)
        chosen, means, ranks, _, _ = choice.choose(table({
            "default": (0.5, 0.2, 12.0), "sigma0=0.1": (0.4, 0.3, 11.0), "max_descent_steps=30": (0.6, 0.1, 13.0)}))
        self.assertEqual(chosen, "sigma0=0.1")
        self.assertAlmostEqual(means["sigma0=0.1"], 5.0 / 3.0)
        self.assertEqual(ranks["max_descent_steps=30"], {"cartpole1": 3, "cartpole3": 1, "rastrigin-10": 3})

    def test_equal_medians_share_their_ranks(self):
        _, means, ranks, _, _ = choice.choose(table({
            "default": (1.0, 1.0, 1.0), "max_descent_steps=30": (1.0, 2.0, 0.5), "max_descent_steps=100": (3.0, 2.0, 0.5)}))
        self.assertEqual(ranks["default"]["cartpole1"], 1.5)
        self.assertEqual(ranks["max_descent_steps=30"]["cartpole1"], 1.5)
        self.assertEqual(ranks["max_descent_steps=100"]["rastrigin-10"], 1.5)
        self.assertEqual(ranks["max_descent_steps=30"]["cartpole3"], 2.5)
        self.assertAlmostEqual(means["default"], (1.5 + 1 + 3) / 3)

    def test_a_tie_goes_to_plain_steps_then_episodes_then_the_smaller_change(self):
        # every candidate has the same medians: the same mean rank
        same = (1.0, 1.0, 1.0)
        self.assertEqual(choice.choose(table({"default": same, "plain_steps": same, "sigma0=0.1": same}))[0],
                         "plain_steps")
        self.assertEqual(choice.choose(table({"leap_iterations=100": same, "sigma0=0.1": same}))[0], "sigma0=0.1")
        self.assertEqual(choice.choose(table({"default": same, "sigma0=0.1": same, "adam_per_leap": same}))[0],
                         "default")
        # sigma0 0.1 is a smaller move from 0.3 than 0.03 is
        self.assertEqual(choice.choose(table({"sigma0=0.03": same, "sigma0=0.1": same}))[0], "sigma0=0.1")

    def test_the_ablation_other_optimizers_and_incomplete_variants_are_not_candidates(self):
        extra = [{"env": e, "optimizer": "boleap", "variant": "ablation", "median": "0.0"} for e in ENVS]
        extra += [{"env": e, "optimizer": "cmaes", "variant": "default", "median": "0.0"} for e in ENVS]
        extra += [{"env": "cartpole1", "optimizer": "boleap", "variant": "sigma0=0.03", "median": "0.0"}]
        chosen, means, _, _, _ = choice.choose(table({"default": (1.0, 1.0, 1.0), "plain_steps": (2.0, 2.0, 2.0)}, extra))
        self.assertEqual(chosen, "default")
        self.assertEqual(set(means), {"default", "plain_steps"})

    def test_the_pair_is_the_two_best_single_moves_on_different_knobs(self):
        # singles by mean rank: J=30, J=100 (same knob: skipped), adam_per_leap, sigma0=0.1
        _, _, _, _, pair = choice.choose(table({
            "default": (5.0, 5.0, 5.0), "max_descent_steps=30": (1.0, 1.0, 1.0),
            "max_descent_steps=100": (2.0, 2.0, 2.0), "adam_per_leap": (3.0, 3.0, 3.0),
            "sigma0=0.1": (4.0, 4.0, 4.0)}))
        self.assertEqual(pair, "max_descent_steps=30 adam_per_leap=true")
        # plain_steps and adam_per_leap are one knob (the descent's step)
        _, _, _, _, pair = choice.choose(table({
            "plain_steps": (1.0, 1.0, 1.0), "adam_per_leap": (2.0, 2.0, 2.0), "leap_iterations=100": (3.0, 3.0, 3.0)}))
        self.assertEqual(pair, "plain_steps=true step_size=0.1 leap_iterations=100")

    def test_the_command_line(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "t.csv")
            rows = table({"default": (0.5, 0.2, 12.0), "sigma0=0.1": (0.4, 0.3, 11.0)})
            with open(path, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=["env", "optimizer", "variant", "median"])
                w.writeheader()
                w.writerows(rows)
            script = os.path.join(SOURCE, "scripts", "boleap_study_choice.py")
            r = subprocess.run([sys.executable, script, path, "--markdown", os.path.join(d, "t.md")],
                               capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("chosen: sigma0=0.1 (mean rank 1.33", r.stdout)
            self.assertIn("| **sigma0=0.1** (chosen) | 0.4 (1) | 0.3 (2) | 11 (1) | 1.33 |", r.stdout)
            with open(os.path.join(d, "t.md")) as f:
                self.assertIn("(chosen)", f.read())
            # a table without the median column: one line naming it, exit 2
            with open(path, "w") as f:
                f.write("env,optimizer,variant\ncartpole1,boleap,default\n")
            r = subprocess.run([sys.executable, script, path], capture_output=True, text=True)
            self.assertEqual(r.returncode, 2)
            self.assertEqual(r.stderr.strip().count("\n"), 0)
            self.assertIn("median", r.stderr)


if __name__ == "__main__":
    unittest.main()
