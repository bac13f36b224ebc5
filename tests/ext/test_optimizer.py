#!/usr/bin/env python3
"""External optimizers for the tests (tests/test_ext.cpp) and the protocol benchmark
(tests/perf/bench_ext.cpp), standard library only, through examples/ext/dsb_protocol.py.

    test_optimizer.py MODE [BATCH]

Modes that follow the protocol: `random` (uniform points from random.Random(seed), BATCH at a
time, default 1), `echo` (asks one random point BATCH times per ask, for timing the protocol),
`echo-binary` (the same in base64, numpy), `stop-early` (10 episodes, then returns), `roundtrip`
(sends back each loss and gradient component as the next point's x[0], x[1]), `roundtrip-binary`
(the same in base64, numpy), `burn` (burns 0.4 s of CPU in a child process it waits for, then
0.02 s of its own before each ask of one random point: a run's cpu_s). Modes that break it, after
3 good episodes: `crash` (exits 3 with a traceback-like stderr line), `garbage` (a line that is
not JSON), `outside` (a point with x[1] = 1.5), `leak-detached` (starts `sleep 300` in a session
of its own holding its stdout, writes its pid to $TEST_OPT_PIDFILE, exits 3), `hang` (sleeps for
an hour), `hang-ignoring-term` (the same with SIGTERM ignored: only SIGKILL ends it), `after-end`
(asks again after the end), `grad` (asks for a gradient, whatever the hello said), `bad-base64` (a
binary ask that is not base64); `bad-probe` fails the probe (exit 4 before its hello). The
version it reports is $TEST_OPT_VERSION (default 1). The hanging modes write their pid to
$TEST_OPT_PIDFILE when it is set, once they hang.
"""
import os
import random
import signal
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "ext"))
import dsb_protocol as dsb  # noqa: E402

MODE = sys.argv[1]
BURN_CODE = "import time\nt = time.process_time()\nwhile time.process_time() - t < {}: pass"
BATCH = int(sys.argv[2]) if len(sys.argv) > 2 else 1


def optimize(s):
    rng = random.Random(s.seed)

    def point():
        return [rng.uniform(lo, hi) for lo, hi in zip(s.lower, s.upper)]

    if MODE == "echo":
        x = point()  # a point with 17-digit coordinates, as an optimizer's are
        while True:
            s.ask([x] * BATCH)
    if MODE == "echo-binary":
        import numpy as np
        xs = np.array([point()] * BATCH)
        while True:
            s.ask_array(xs)
    if MODE == "roundtrip-binary":
        import numpy as np
        x = np.full((1, s.dim), 0.1)
        while True:
            losses, grads = s.ask_array(x, grad=True)
            x = np.zeros((1, s.dim))
            x[0, 0], x[0, 1] = losses[0], grads[0, 1]
    if MODE == "roundtrip":
        # each point carries the last loss and gradient component back: the harness records it,
        # so the test sees whether numbers survive both directions bit for bit
        x = [0.1] * s.dim
        while True:
            loss, grad = s.evaluate_with_grad(x)
            x = [loss, grad[1]] + [0.0] * (s.dim - 2)
    if MODE == "burn":
        # CPU to be counted in the run's cpu_s: 0.4 s in a child process it waits for, then
        # 0.02 s of its own before each ask of one point
        import subprocess
        subprocess.run([sys.executable, "-c", BURN_CODE.format(0.4)], check=True)
        while True:
            exec(BURN_CODE.format(0.02))
            s.evaluate(point())
    if MODE == "stop-early":
        for _ in range(10):
            s.evaluate(point())
        return
    if MODE in ("random", "after-end"):
        try:
            while True:
                s.ask([point() for _ in range(BATCH)])
        except dsb.BudgetEnd:
            if MODE == "random":
                raise
        # after-end: read the end, then ask once more
        s._send({"ask": [point()]})
        time.sleep(1.0)
        sys.exit(0)
    for _ in range(3):
        s.evaluate(point())
    if MODE == "leak-detached":
        # a child in a session of its own (setsid), holding our stdout, its pid in $TEST_OPT_PIDFILE;
        # then a crash: the child must end with the run
        import subprocess
        child = subprocess.Popen(["sleep", "300"], start_new_session=True)
        with open(os.environ["TEST_OPT_PIDFILE"] + ".tmp", "w") as f:
            f.write(str(child.pid))
        os.rename(os.environ["TEST_OPT_PIDFILE"] + ".tmp", os.environ["TEST_OPT_PIDFILE"])
        sys.exit(3)
    if MODE == "crash":
        sys.stderr.write("Traceback (most recent call last):\nZeroDivisionError: division by zero\n")
        sys.exit(3)
    if MODE == "garbage":
        sys.stdout.write("this is not json\n")
        sys.stdout.flush()
    elif MODE == "outside":
        x = point()
        x[1] = 1.5
        s.evaluate(x)
    elif MODE in ("hang", "hang-ignoring-term"):
        if MODE == "hang-ignoring-term":
            signal.signal(signal.SIGTERM, signal.SIG_IGN)
        if os.environ.get("TEST_OPT_PIDFILE"):
            with open(os.environ["TEST_OPT_PIDFILE"] + ".tmp", "w") as f:
                f.write(str(os.getpid()))
            os.rename(os.environ["TEST_OPT_PIDFILE"] + ".tmp", os.environ["TEST_OPT_PIDFILE"])
        time.sleep(3600)
    elif MODE == "bad-base64":
        s._send({"ask": "not base64!"})
    elif MODE == "grad":
        s._send({"ask": [point()], "grad": True})
    else:
        sys.exit("test_optimizer.py: unknown mode " + MODE)
    s._in.readline()
    time.sleep(3600)


if MODE == "bad-probe":
    sys.stderr.write("cannot start: missing module\n")
    sys.exit(4)
dsb.main("test-" + MODE, os.environ.get("TEST_OPT_VERSION", "1"), optimize)
