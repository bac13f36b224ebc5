"""The optimizer's side of diffsim-bench's external optimizer protocol, version 1
(docs/ext-protocol.md). Standard library only; copy it next to your optimizer.

    import dsb_protocol as dsb

    def optimize(s):                      # s: a Session
        rng = random.Random(s.seed)       # seed yourself from the hello: reruns give the same bits
        while True:                       # until the budget ends (BudgetEnd, caught by run)
            x = [rng.uniform(lo, hi) for lo, hi in zip(s.lower, s.upper)]
            loss = s.evaluate(x)

    dsb.run("my-random", "1", optimize)

run() answers the harness's probe (name and version, before the grid runs) and each run's hello,
calls optimize(session), and exits 0 when the budget ends. Everything the harness says goes
through stdin and stdout: write your logs to stderr.
"""
import base64
import json
import math
import sys

PROTOCOL = 1


class BudgetEnd(Exception):
    """The budget is spent: the harness has sent {"end": "budget"}. Let it pass out of optimize()."""


class ProtocolError(Exception):
    """The harness said something this client does not understand."""


def _plain(o):
    # numpy arrays and scalars as json.dumps wants them (anything with tolist())
    if hasattr(o, "tolist"):
        return o.tolist()
    raise TypeError("cannot send %r as a number or a list of numbers" % (o,))


def _loss(v):
    # a failed episode (the simulation blew up) arrives as null: worse than any loss
    return math.inf if v is None else float(v)


class Session:
    """One run: the hello's facts and the calls that evaluate points."""

    def __init__(self, hello, inp, out):
        self.env = hello["env"]
        self.dim = int(hello["dim"])
        self.lower = [float(v) for v in hello["lower"]]
        self.upper = [float(v) for v in hello["upper"]]
        self.budget = int(hello["budget"])
        self.gradient = bool(hello["gradient"])  # whether grad=True asks are allowed
        self.seed = int(hello["seed"])           # the run's seed (0 <= seed < 2**64)
        self.used = 0
        self.remaining = self.budget
        self._in, self._out = inp, out

    def _send(self, message):
        self._out.write(json.dumps(message, allow_nan=False, default=_plain) + "\n")
        self._out.flush()

    def _receive(self):
        line = self._in.readline()
        if not line:
            raise BudgetEnd()  # the harness closed our input: nothing more will be answered
        message = json.loads(line)
        if "end" in message:
            self.remaining = 0
            raise BudgetEnd()
        return message

    def ask(self, points, grad=False):
        """Evaluates points (a list of points, each a list or numpy array of dim floats in
        [lower, upper]; or a 2-D numpy array, one point per row) as consecutive
        episodes. Returns (losses, grads): losses as floats (inf for a failed episode), grads a
        list of gradient lists (None for a failed episode) when grad, else None. When the budget
        ends inside the batch, only the points that fit are evaluated: the lists are shorter."""
        if self.remaining <= 0:
            raise BudgetEnd()
        reply = self._exchange(points, grad)
        losses = [_loss(v) for v in reply["losses"]]
        return losses, (reply["grads"] if grad else None)

    def _exchange(self, points, grad):
        """sends one ask (points as a JSON list or a base64 string) and returns the reply, with
        used and remaining taken from it"""
        message = {"ask": points}
        if grad:
            message["grad"] = True
        self._send(message)
        reply = self._receive()
        if "losses" not in reply:
            raise ProtocolError("unexpected reply %r" % (reply,))
        self.used, self.remaining = int(reply["used"]), int(reply["remaining"])
        return reply

    def ask_array(self, xs, grad=False):
        """ask() for numpy users, in the protocol's binary form: xs a 2-D array (one point per
        row) sent as base64 of little-endian doubles, exact and far cheaper than JSON text at
        high dimension (docs/ext-protocol.md, "Binary points"). Returns (losses, grads) as numpy
        arrays: losses with inf for a failed episode; grads (rows x dim, NaN rows for failed
        episodes) when grad, else None; shorter than xs when the budget ended inside the batch."""
        import numpy as np
        if self.remaining <= 0:
            raise BudgetEnd()
        xs = np.ascontiguousarray(np.asarray(xs, dtype="<f8").reshape(-1, self.dim))
        reply = self._exchange(base64.b64encode(xs.tobytes()).decode("ascii"), grad)
        losses = np.frombuffer(base64.b64decode(reply["losses"]), dtype="<f8").copy()
        losses[np.isnan(losses)] = np.inf
        grads = None
        if grad:
            grads = np.frombuffer(base64.b64decode(reply["grads"]), dtype="<f8").reshape(-1, self.dim).copy()
        return losses, grads

    def evaluate_array(self, xs):
        """evaluate_batch() through ask_array(): a numpy array of losses, BudgetEnd when the budget
        ended inside the batch."""
        losses, _ = self.ask_array(xs)
        if len(losses) < len(xs):
            raise BudgetEnd()
        return losses

    def evaluate(self, x):
        """One episode: the loss at x."""
        losses, _ = self.ask([x])
        if not losses:
            raise BudgetEnd()
        return losses[0]

    def evaluate_with_grad(self, x):
        """One episode with the gradient: (loss, gradient list or None when the episode failed)."""
        losses, grads = self.ask([x], grad=True)
        if not losses:
            raise BudgetEnd()
        return losses[0], grads[0]

    def evaluate_batch(self, xs):
        """A population, one episode each, in order. Raises BudgetEnd when the budget ended inside
        the batch (the points that fit were evaluated and recorded)."""
        losses, _ = self.ask(xs)
        if len(losses) < len(xs):
            raise BudgetEnd()
        return losses


def run(name, version, optimize, inp=None, out=None):
    """Speaks the protocol on stdin/stdout: answers the hello with name and version, then calls
    optimize(session) until the budget ends. Returns the process's exit status (0)."""
    inp = inp or sys.stdin
    out = out or sys.stdout
    line = inp.readline()
    if not line:
        return 0
    hello = json.loads(line)
    if hello.get("protocol") != PROTOCOL:
        sys.stderr.write("dsb_protocol: the harness speaks protocol %r, this client %d\n"
                         % (hello.get("protocol"), PROTOCOL))
        return 1
    out.write(json.dumps({"hello": PROTOCOL, "name": name, "version": version}) + "\n")
    out.flush()
    if hello.get("probe"):
        inp.readline()  # {"end": "probe"}
        return 0
    session = Session(hello, inp, out)
    try:
        optimize(session)
    except BudgetEnd:
        # read to the end of our input (the harness's {"end": "budget"}), then exit 0
        while inp.readline():
            pass
    # returning before the budget ends is allowed: the run ends there, with fewer episodes
    return 0


def main(name, version, optimize):
    """run() as a program: sys.exit with its status."""
    sys.exit(run(name, version, optimize))
