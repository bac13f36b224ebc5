"""The envs and optimizers a harness binary knows, read from `harness list`.

The claims table uses it to tell an env the harness does not have ("env missing") from an env whose
runs are not in the database yet, and to know which optimizers `harness --all` runs on an env (the
rivals of an "a_best" claim): every listed optimizer except `ext:NAME`, the gradient ones only on
differentiable envs, the RL ones only on RL envs.
"""
from __future__ import annotations

import os
import re
import subprocess
from dataclasses import dataclass


class RegistryError(Exception):
    """The harness cannot be run or its `list` output cannot be read (one-line message)."""


@dataclass
class Registry:
    source: str      # the harness binary asked
    envs: dict       # name -> (differentiable, rl)
    optimizers: dict  # name -> (needs gradient, needs rl), in `harness list` order
    # results versions: {"env": name -> version, "optimizer": name -> version, "run": version}
    versions: dict = None

    def current_versions(self, env: str, optimizer: str):
        """The results versions (env, optimizer, run) this harness gives a run of env and
        optimizer (an env variant has its listed env's, ext:NAME the ext: adapter's), or None
        when it does not know the env or the optimizer or lists no versions."""
        if not self.versions or self.versions.get("run") is None:
            return None
        entry = self.env_entry(env)
        opt = "ext:NAME" if optimizer.startswith("ext:") else optimizer
        e, o = self.versions["env"].get(entry), self.versions["optimizer"].get(opt)
        if e is None or o is None:
            return None
        return (e, o, self.versions["run"])

    def env_entry(self, name: str):
        """The listed env `name` is, or is a variant of: fluid-hN and plb-NAME-hN (the first N env
        steps), NAME-D of a synthetic family listed at another dimension (sphere-2 of sphere-10).
        None when the harness has no such env."""
        if name in self.envs:
            return name
        base = base_env(name)
        if base != name and base in self.envs:
            return base
        m = re.fullmatch(r"(.+)-[0-9]+", name)
        if m:
            for listed in self.envs:
                if re.fullmatch(re.escape(m.group(1)) + r"-[0-9]+", listed):
                    return listed
        return None

    def has_env(self, name: str) -> bool:
        return self.env_entry(name) is not None

    def optimizers_for(self, env: str) -> list:
        """The optimizers `harness --all` runs on env (empty when the env is not known)."""
        entry = self.env_entry(env)
        if entry is None:
            return []
        differentiable, rl = self.envs[entry]
        return [o for o, (grad, needs_rl) in self.optimizers.items()
                if (differentiable or not grad) and (rl or not needs_rl)]


def base_env(name: str) -> str:
    """The env of `harness list` a short-horizon variant belongs to: fluid-h5 -> fluid,
    plb-table-h5 -> plb-table; any other name is its own env."""
    m = re.fullmatch(r"((?:fluid|plb-[a-z]+))-h[0-9]+", name)
    return m.group(1) if m else name


def _yes(word: str, where: str) -> bool:
    if word not in ("yes", "no"):
        raise RegistryError(f"`harness list`: expected yes or no in '{where}'")
    return word == "yes"


def _table(lines: list, header: str) -> list:
    """The rows (split on whitespace) under the line that starts with `header`, to a blank line."""
    start = next((k for k, line in enumerate(lines) if line.split()[:1] == [header]), None)
    if start is None:
        raise RegistryError(f"`harness list`: no '{header}' table")
    rows = []
    for line in lines[start + 1:]:
        if not line.strip():
            break
        rows.append(line.split())
    return rows


def _version(word: str, where: str) -> int:
    if not word.isdigit():
        raise RegistryError(f"`harness list`: expected a results version in '{where}', got '{word}'")
    return int(word)


def parse(text: str, source: str = "harness list") -> Registry:
    """Registry from the text of `harness list`: the env table (name, results version, dim,
    differentiable, rl, description), the optimizer table (name, results version, needs gradient,
    needs rl, seed use, description) and the line 'run code version N'."""
    lines = text.splitlines()
    env_rows = [r for r in _table(lines, "env") if len(r) >= 5]
    opt_rows = [r for r in _table(lines, "optimizer") if len(r) >= 4]
    envs = {r[0]: (_yes(r[3], r[0]), _yes(r[4], r[0])) for r in env_rows}
    opts = {r[0]: (_yes(r[2], r[0]), _yes(r[3], r[0])) for r in opt_rows
            if ":" not in r[0]}     # ext:NAME is a placeholder, not an optimizer
    if not envs or not opts:
        raise RegistryError("`harness list` lists no env or no optimizer")
    run = next((line.split()[-1] for line in lines if line.startswith("run code version ")), None)
    versions = {
        "env": {r[0]: _version(r[1], r[0]) for r in env_rows},
        "optimizer": {r[0]: _version(r[1], r[0]) for r in opt_rows},
        "run": _version(run, "run code version") if run is not None else None,
    }
    return Registry(source, envs, opts, versions)


def load(harness: str) -> Registry:
    """Runs `HARNESS list` and reads its tables."""
    try:
        proc = subprocess.run([harness, "list"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired) as e:
        raise RegistryError(f"cannot run '{harness} list': {e}") from None
    if proc.returncode != 0:
        raise RegistryError(f"'{harness} list' exited {proc.returncode}")
    return parse(proc.stdout, harness)


def default_harness(source_root: str):
    """$DSB_HARNESS, else build/bin/harness of this source tree, if executable; else None."""
    for path in (os.environ.get("DSB_HARNESS"), os.path.join(source_root, "build", "bin", "harness")):
        if path and os.access(path, os.X_OK):
            return path
    return None
