#pragma once
// A probe: one short run of an (env, optimizer) pair, timed as a grid runs it (journal recorded,
// nothing stored), then replayed from its journal and timed again, for `harness calibrate`
// (plan/cost_model.hpp keeps what it measured).
#include "envs/core/env.hpp"
#include "harness/core/probe_timing.hpp"
#include "harness/core/run_spec.hpp"

namespace dsb {

// runs `spec` (its budget: the probe's episodes) on `env` and times it, then its replay (not
// replayed when the optimizer drew before its first episode: no later seed shares any of it, so
// it is not timed; half of calibrate's time on CMA-ES in 400-D)
ProbeTiming time_probe(const RunSpec& spec, const Env& env);

}  // namespace dsb
