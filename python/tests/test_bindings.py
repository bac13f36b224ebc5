#!/usr/bin/env python3
"""Tests of the Python bindings (import diffsim_bench), run by ctest (test python_bindings).

Loss and gradient equal `harness eval --grad` bit for bit; the RL view equals loss() for the
same actions; bad input raises ValueError naming the value; threads give the same bits; the GIL
is released while a rollout runs; env options (make's keywords) as `harness eval --set` takes them.

Run by hand: PYTHONPATH=build/python DSB_HARNESS=build/bin/harness /usr/bin/python3 python/tests/test_bindings.py -v
"""
import json
import math
import os
import pathlib
import re
import signal
import subprocess
import tempfile
import threading
import time
import unittest

import numpy as np

import diffsim_bench as dsb

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
HARNESS = os.environ.get("DSB_HARNESS", os.path.join(ROOT, "build", "bin", "harness"))

# the envs compared with `harness eval`: rigid, synthetic, cloth, MPM
EVAL_ENVS = ["cartpole1", "bounce", "sphere-10", "flip", "fluid-h5"]


def seeded_point(dim, seed, amplitude=0.8):
    return np.random.default_rng(seed).uniform(-amplitude, amplitude, dim)


def harness_eval(env, x, grad=True, sets=()):
    """`harness eval` at x (written in the shortest form that reads back as the same doubles)."""
    cmd = [HARNESS, "eval", "--env", env, "--x=" + ",".join(repr(float(v)) for v in x)]
    if grad:
        cmd.append("--grad")
    for s in sets:
        cmd += ["--set", s]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out)  # exact doubles (JSON null for nan)


def bits(v):
    """A double's exact bits as text (float.hex); JSON null and nan both as 'nan'."""
    return "nan" if v is None or math.isnan(v) else float(v).hex()


def actions_of(x, rl, dim):
    """x's per-step actions: x holds segments of action_dim values, each held for horizon/segments steps."""
    segments = dim // rl.action_dim
    per = rl.horizon // segments
    for k in range(rl.horizon):
        s = k // per
        yield x[s * rl.action_dim:(s + 1) * rl.action_dim]


class RegistryTest(unittest.TestCase):
    def test_envs_lists_the_grid_with_metadata(self):
        envs = {e["name"]: e for e in dsb.envs()}
        self.assertEqual(envs["cartpole1"]["dim"], 200)
        self.assertTrue(envs["cartpole1"]["differentiable"])
        self.assertTrue(envs["cartpole1"]["rl"])
        self.assertFalse(envs["bounce"]["rl"])
        self.assertEqual(envs["fluid"]["metric"], "cube_height")
        self.assertIsNone(envs["sphere-10"]["metric"])
        self.assertIn("ladle", envs["fluid"]["description"])
        # the same names as `harness list`
        listed = subprocess.run([HARNESS, "list"], check=True, capture_output=True, text=True).stdout
        names = [line.split()[0] for line in listed.split("\n\n")[0].splitlines()[1:]]
        self.assertEqual(names, [e["name"] for e in dsb.envs()])

    def test_make_gives_metadata_and_config(self):
        env = dsb.make("fluid-h5")
        self.assertEqual((env.name, env.dim, env.differentiable, env.supports_rl), ("fluid-h5", 10, True, True))
        self.assertEqual(env.threads, 1)
        self.assertEqual(env.metric, "cube_height")
        cfg = env.config
        self.assertIsInstance(cfg, dict)
        self.assertEqual(cfg["env_steps"], 5)
        self.assertIn("fluid-h5", repr(env))
        fluid = {e["name"]: e for e in dsb.envs()}["fluid"]
        self.assertEqual(dsb.make("fluid").info, fluid)

    def test_unknown_env_and_bad_threads_raise_value_error(self):
        with self.assertRaisesRegex(ValueError, "no-such-env"):
            dsb.make("no-such-env")
        with self.assertRaisesRegex(ValueError, "sphere-0"):
            dsb.make("sphere-0")
        with self.assertRaisesRegex(ValueError, "threads must be >= 1, got 0"):
            dsb.make("sphere-3", threads=0)

    def test_threads_are_capped_at_the_usable_cpus(self):
        # more threads than CPUs only slow a rollout down (1,024 threads made a 0.09 s rollout 20 s)
        cpus = len(os.sched_getaffinity(0))
        with self.assertRaisesRegex(ValueError, f"threads {cpus + 1} is more than the {cpus} CPUs"):
            dsb.make("sphere-3", threads=cpus + 1)
        with self.assertRaisesRegex(ValueError, "threads 10000 is more than"):
            dsb.make("sphere-3", threads=10000)
        self.assertEqual(dsb.make("sphere-3", threads=cpus).threads, cpus)


class EvalEqualityTest(unittest.TestCase):
    """loss(x) and loss_and_grad(x) against `harness eval --grad`, bit for bit."""

    def test_loss_and_gradient_equal_harness_eval(self):
        for name in EVAL_ENVS:
            env = dsb.make(name)
            for seed in (1, 2):
                x = seeded_point(env.dim, seed)
                with self.subTest(env=name, seed=seed):
                    ref = harness_eval(name, x)
                    loss, grad = env.loss_and_grad(x)
                    self.assertIsInstance(loss, float)
                    self.assertIsInstance(grad, np.ndarray)
                    self.assertEqual(grad.shape, (env.dim,))
                    self.assertEqual(grad.dtype, np.float64)
                    self.assertEqual(bits(loss), bits(ref["loss"]))
                    self.assertEqual([bits(g) for g in grad], [bits(g) for g in ref["grad"]])
                    if "metric" in ref:
                        self.assertEqual(bits(env.last_metric()), bits(ref["metric"][env.metric]))
                    # the value path gives the same loss, from a list as from an array
                    self.assertEqual(bits(env.loss(list(x))), bits(ref["loss"]))

    def test_loss_matches_harness_eval_without_gradient(self):
        x = seeded_point(3, 7)
        self.assertEqual(bits(dsb.make("bounce").loss(x)), bits(harness_eval("bounce", x, grad=False)["loss"]))

    def test_box_corners_are_accepted(self):
        env = dsb.make("sphere-10")
        x = np.array([-1.0, 1.0] * 5)
        self.assertEqual(bits(env.loss(x)), bits(harness_eval("sphere-10", x)["loss"]))


class EnvOptionsTest(unittest.TestCase):
    """make(NAME, KEY=VALUE) takes an env's options as `harness --set NAME.KEY=VALUE` does."""

    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.target = os.path.join(self.dir.name, "target.npy")
        t = np.zeros((64, 64, 64))
        t[24:40, 0:12, 24:40] = 2e-4
        np.save(self.target, t.astype(np.float32))

    def tearDown(self):
        self.dir.cleanup()

    def test_target_file_gives_harness_evals_bits(self):
        env = dsb.make("plb-pinch-h5", target=self.target)
        self.assertEqual(env.config["target"]["shape"], [64, 64, 64])
        self.assertEqual(len(env.config["target"]["values_fnv1a64"]), 16)
        # a pathlib.Path names the same file: the same config
        self.assertEqual(dsb.make("plb-pinch-h5", target=pathlib.Path(self.target)).config, env.config)
        self.assertNotEqual(dsb.make("plb-pinch-h5").config, env.config)
        x = seeded_point(env.dim, 3)
        ref = harness_eval("plb-pinch-h5", x, grad=False, sets=["plb-pinch-h5.target=" + self.target])
        self.assertEqual(bits(env.loss(x)), bits(ref["loss"]))
        self.assertNotEqual(bits(dsb.make("plb-pinch-h5").loss(x)), bits(ref["loss"]))

    def test_a_fifo_as_a_target_is_refused_at_once(self):
        # open(2) of a FIFO waits for a writer; the alarm turns a regression into a failure, not a hang
        fifo = os.path.join(self.dir.name, "fifo-target.npy")
        os.mkfifo(fifo)
        signal.signal(signal.SIGALRM, lambda *_: (_ for _ in ()).throw(TimeoutError("make() blocked on a FIFO")))
        signal.alarm(20)
        try:
            with self.assertRaisesRegex(ValueError, re.escape(fifo) + ": is a FIFO \\(named pipe\\), not a regular file"):
                dsb.make("plb-pinch-h5", target=fifo)
        finally:
            signal.alarm(0)

    def test_bad_options_raise_value_error_naming_them(self):
        missing = os.path.join(self.dir.name, "missing.npy")
        with self.assertRaisesRegex(ValueError, "plb-pinch-h5.target: " + missing + ": cannot open"):
            dsb.make("plb-pinch-h5", target=missing)
        with self.assertRaisesRegex(ValueError, "has no option 'tagret'"):
            dsb.make("plb-pinch-h5", tagret=self.target)
        with self.assertRaisesRegex(ValueError, "env 'sphere-3' takes no options, got 'target'"):
            dsb.make("sphere-3", target=self.target)
        np.save(os.path.join(self.dir.name, "flat.npy"), np.zeros((64, 64)))
        with self.assertRaisesRegex(ValueError, r"shape \(64, 64\) is not a target grid's"):
            dsb.make("plb-pinch-h5", target=os.path.join(self.dir.name, "flat.npy"))


    def test_paths_are_str_bytes_or_path_like(self):
        env = dsb.make("plb-pinch-h5", target=self.target)
        # bytes: the file's name as the OS has it, never the text "b'...'"
        self.assertEqual(dsb.make("plb-pinch-h5", target=os.fsencode(self.target)).config, env.config)
        odd = os.path.join(os.fsencode(self.dir.name), b"t\xff.npy")  # not UTF-8
        with open(self.target, "rb") as src, open(odd, "wb") as dst:
            dst.write(src.read())
        self.assertEqual(dsb.make("plb-pinch-h5", target=odd).config, env.config)
        self.assertEqual(dsb.make("plb-pinch-h5", target=os.fsdecode(odd)).config, env.config)
        missing = os.path.join(self.dir.name, "missing.npy")
        with self.assertRaises(ValueError) as caught:
            dsb.make("plb-pinch-h5", target=os.fsencode(missing))
        self.assertIn(missing, str(caught.exception))
        self.assertNotIn("b'", str(caught.exception))
        # what is no path is refused as such, naming it
        for value, shown in ((5, "int 5"), (None, "NoneType None"), (1.5, "float 1.5"), ([self.target], "list")):
            with self.assertRaisesRegex(TypeError, r"plb-pinch-h5\.target must be a path \(str, bytes or "
                                                   r"os\.PathLike\), got " + re.escape(shown)):
                dsb.make("plb-pinch-h5", target=value)
        with self.assertRaisesRegex(ValueError, "null byte"):
            dsb.make("plb-pinch-h5", target=self.target + "\0x")
        # threads: an int, not a bool or a float
        with self.assertRaisesRegex(TypeError, "threads must be an int, got bool True"):
            dsb.make("bounce", threads=True)
        with self.assertRaisesRegex(TypeError, "threads must be an int, got float 1.0"):
            dsb.make("bounce", threads=1.0)
        with self.assertRaisesRegex(ValueError, "threads must be >= 1, got -3"):
            dsb.make("bounce", threads=-3)

    def test_a_target_must_be_a_mass_grid(self):
        t = np.zeros((64, 64, 64))
        t[24:40, 0:12, 24:40] = 2e-4
        t[3, 4, 5] = -5.0
        bad = os.path.join(self.dir.name, "negative.npy")
        np.save(bad, t)
        with self.assertRaisesRegex(ValueError, re.escape(bad) + r": value -5 at \[3, 4, 5\] is negative"):
            dsb.make("plb-pinch-h5", target=bad)
        zero = os.path.join(self.dir.name, "zero.npy")
        np.save(zero, np.zeros((64, 64, 64)))
        with self.assertRaisesRegex(ValueError, "no positive mass"):
            dsb.make("plb-pinch-h5", target=zero)


class RlViewTest(unittest.TestCase):
    """The RL view driven with x's per-step actions gives loss(x), bit for bit."""

    def check_replay(self, name, seed):
        env = dsb.make(name)
        x = seeded_point(env.dim, seed)
        rl = env.rl()
        rl.reset()
        obs = rl.observe()
        self.assertEqual(obs.shape, (rl.observation_dim,))
        with self.assertRaisesRegex(RuntimeError, "not done"):
            rl.final_loss()
        steps = 0
        for a in actions_of(x, rl, env.dim):
            self.assertFalse(rl.done())
            rl.step(a)
            steps += 1
        self.assertEqual(steps, rl.horizon)
        self.assertTrue(rl.done())
        self.assertEqual(bits(rl.final_loss()), bits(env.loss(x)))
        with self.assertRaisesRegex(RuntimeError, "done; call reset"):
            rl.step(np.zeros(rl.action_dim))
        # a second episode after reset() gives the same bits
        rl.reset()
        for a in actions_of(x, rl, env.dim):
            rl.step(a)
        self.assertEqual(bits(rl.final_loss()), bits(env.loss(x)))
        return rl

    def test_cartpole1(self):
        rl = self.check_replay("cartpole1", 3)
        self.assertEqual((rl.action_dim, rl.horizon, rl.action_repeat), (2, 100, 1))

    def test_fluid_h5(self):
        rl = self.check_replay("fluid-h5", 4)
        self.assertEqual((rl.action_dim, rl.horizon), (2, 5))

    def test_bad_actions_and_envs_without_rl(self):
        rl = dsb.make("cartpole1").rl()
        with self.assertRaisesRegex(ValueError, "action has 3 values, env 'cartpole1' needs 2"):
            rl.step([0.0, 0.0, 0.0])
        with self.assertRaisesRegex(ValueError, "action: value nan at position 1"):
            rl.step([0.0, float("nan")])
        with self.assertRaisesRegex(ValueError, "bounce"):
            dsb.make("bounce").rl()


class BadInputTest(unittest.TestCase):
    def test_wrong_length_names_the_length(self):
        env = dsb.make("bounce")
        with self.assertRaisesRegex(ValueError, "x has 4 values, env 'bounce' needs 3"):
            env.loss(np.zeros(4))
        with self.assertRaisesRegex(ValueError, "x has 2 values"):
            env.loss_and_grad([0.0, 0.0])
        with self.assertRaisesRegex(ValueError, "x must be 1-D, got 2 dimensions"):
            env.loss(np.zeros((1, 3)))
        with self.assertRaises(TypeError):
            env.loss(["a", "b", "c"])

    def test_only_real_numbers_are_numbers(self):
        env = dsb.make("bounce")
        refused = [
            (["0.1", 0, 0], r"x: value '0\.1' at position 0 is a str, not a real number"),
            ([0, None, 0], r"x: value None at position 1 is None, not a real number"),
            ([0, 0, True], r"x: value True at position 2 is a bool, not a real number"),
            ([np.bool_(False), 0, 0], r"x: value (np\.)?False(_)? at position 0 is a bool"),
            ([0, 0.5j, 0], r"x: value 0\.5j at position 1 is a complex, not a real number"),
            (np.array([True, False, True]), r"x must hold real numbers, got a numpy array of dtype bool"),
            (np.array(["0.1", "0", "0"]), r"x must hold real numbers, got a numpy array of dtype <U3"),
            (np.array([0.1, "a", 0], dtype=object), r"x: value 'a' at position 1 is a str"),
            ("0.1,0,0", r"x must be a 1-D numpy array or sequence of numbers, got str '0\.1,0,0'"),
            (["\x1b[2J", 0, 0], r"x: value '\\x1b\[2J' at position 0 is a str"),
        ]
        for x, message in refused:
            with self.subTest(x=repr(x)):
                with self.assertRaisesRegex(TypeError, message) as caught:
                    env.loss(x)
                self.assertNotIn("\x1b", str(caught.exception))
                with self.assertRaises(TypeError):
                    env.loss_and_grad(x)
        with self.assertRaisesRegex(ValueError, r"x: value 1000000000.* at position 0 is too large for a double"):
            env.loss([10 ** 400, 0, 0])
        with self.assertRaisesRegex(TypeError, r"action: value '0' at position 1 is a str"):
            dsb.make("cartpole1").rl().step([0.0, "0"])
        # every kind of real number, as the same doubles
        reference = bits(env.loss([0.0, 0.5, 0.25]))
        for x in ([0, 0.5, 0.25], [np.int64(0), np.float64(0.5), np.float32(0.25)], (0, 0.5, 0.25),
                  np.array([0.0, 0.5, 0.25], dtype=np.float32), np.array([0.0, 0.5, 0.25], dtype=object),
                  [np.array(0.0), 0.5, 0.25]):
            with self.subTest(x=repr(x)):
                self.assertEqual(bits(env.loss(x)), reference)
        self.assertEqual(bits(env.loss(np.zeros(3, dtype=np.int32))), bits(env.loss([0.0, 0.0, 0.0])))

    def test_value_outside_the_box_names_the_value(self):
        env = dsb.make("bounce")
        with self.assertRaisesRegex(ValueError, r"x: value 1\.5 at position 2 is outside \[-1, 1\]"):
            env.loss([0.0, 0.0, 1.5])
        with self.assertRaisesRegex(ValueError, r"value -1\.0000001 at position 0"):
            env.loss_and_grad([-1.0000001, 0.0, 0.0])
        with self.assertRaisesRegex(ValueError, "value nan at position 1"):
            env.loss([0.0, float("nan"), 0.0])


class ThreadsAndGilTest(unittest.TestCase):
    def test_two_threads_give_the_same_bits(self):
        x = seeded_point(10, 5)
        one = dsb.make("fluid-h5", threads=1).loss_and_grad(x)
        two_env = dsb.make("fluid-h5", threads=2)
        self.assertEqual(two_env.threads, 2)
        two = two_env.loss_and_grad(x)
        self.assertEqual(bits(one[0]), bits(two[0]))
        self.assertEqual([bits(g) for g in one[1]], [bits(g) for g in two[1]])
        self.assertEqual(bits(two_env.loss(x)), bits(one[0]))

    def test_gil_is_released_during_a_rollout(self):
        # a ticker thread records a time stamp every millisecond; were the GIL held through the
        # rollout, it could not run between the rollout's first and last few milliseconds
        env = dsb.make("fluid-h5")
        x = seeded_point(10, 6)
        env.loss(x)  # build the model first
        stamps, stop = [], threading.Event()

        def ticker():
            while not stop.is_set():
                stamps.append(time.perf_counter())
                time.sleep(0.001)

        t = threading.Thread(target=ticker)
        t.start()
        time.sleep(0.01)
        t0 = time.perf_counter()
        env.loss_and_grad(x)
        t1 = time.perf_counter()
        stop.set()
        t.join()
        span = t1 - t0
        self.assertGreater(span, 0.05, "the rollout is too short for this check")
        middle = [s for s in stamps if t0 + 0.25 * span < s < t1 - 0.25 * span]
        self.assertGreater(len(middle), 0, f"no tick during the middle half of a {span:.3f} s rollout")

    def test_concurrent_rollouts_on_two_envs_give_the_serial_bits(self):
        xs = [seeded_point(10, s) for s in (8, 9)]
        serial = [dsb.make("fluid-h5").loss_and_grad(x) for x in xs]
        results = [None, None]

        def run(i):
            results[i] = dsb.make("fluid-h5").loss_and_grad(xs[i])

        threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        for (l1, g1), (l2, g2) in zip(serial, results):
            self.assertEqual(bits(l1), bits(l2))
            self.assertEqual([bits(g) for g in g1], [bits(g) for g in g2])


if __name__ == "__main__":
    unittest.main()
