#!/usr/bin/env python3
"""Loss and gradient of an env through the Python bindings, checked against `harness eval`.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/loss_and_grad.py [--env bounce] [--seed 0]

Draws a seeded point x in [-1, 1]^dim, computes loss and dLoss/dx with diffsim_bench, runs
`harness eval --env ENV --x X --grad` on the same x and prints both; exits 1 unless they agree
bit for bit (ctest runs it: python_example_loss_and_grad).
"""
import argparse
import json
import math
import os
import subprocess
import sys

import numpy as np

try:
    import diffsim_bench as dsb
except ImportError as e:
    sys.exit(f"loss_and_grad.py: {e}; build the module (needs python3-dev, pybind11-dev) and run with "
             "PYTHONPATH=build/python /usr/bin/python3")

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--env", default="bounce", help="env name (default bounce)")
    p.add_argument("--seed", type=int, default=0, help="seed of the point (default 0)")
    p.add_argument("--threads", type=int, default=1, help="threads inside the rollout (same bits)")
    p.add_argument("--harness", default=os.path.join(ROOT, "build", "bin", "harness"),
                   help="the harness binary (default build/bin/harness)")
    args = p.parse_args()

    # through the bindings
    env = dsb.make(args.env, threads=args.threads)
    x = np.random.default_rng(args.seed).uniform(-1.0, 1.0, env.dim)
    loss, grad = env.loss_and_grad(x)

    # through the harness: x written in the shortest form that reads back as the same doubles
    cmd = [args.harness, "eval", "--env", args.env, "--x=" + ",".join(repr(float(v)) for v in x), "--grad"]
    ref = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
    ref_loss = math.nan if ref["loss"] is None else ref["loss"]
    ref_grad = np.array([math.nan if g is None else g for g in ref["grad"]])

    def show(v):
        return "[" + ", ".join(repr(float(e)) for e in v) + "]"

    print(f"env {env.name} (dim {env.dim}), x = {show(x)}")
    print(f"bindings:      loss {loss!r}, grad {show(grad)}")
    print(f"harness eval:  loss {ref_loss!r}, grad {show(ref_grad)}")

    def same(a, b):
        return (math.isnan(a) and math.isnan(b)) or float(a).hex() == float(b).hex()

    agree = same(loss, ref_loss) and len(grad) == len(ref_grad) and all(map(same, grad, ref_grad))
    print("bit for bit: " + ("equal" if agree else "DIFFERENT"))
    return 0 if agree else 1


if __name__ == "__main__":
    sys.exit(main())
