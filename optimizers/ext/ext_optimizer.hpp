#pragma once
// External optimizers: a program that speaks the JSON-lines protocol of docs/ext-protocol.md
// (version kExtProtocol) over its stdin and stdout, started once per run. The harness keeps the
// budget, the records and the seed; the program only proposes points. Named `ext:NAME` and
// configured on the command line with `--ext NAME='COMMAND'`.
#include <cstdint>
#include <memory>
#include <string>

#include "optimizers/core/optimizer.hpp"

namespace dsb {

inline constexpr int kExtProtocol = 1;
inline constexpr double kExtDefaultTimeoutS = 60.0;

// one `--ext NAME=COMMAND`, with what the program said of itself when probed (ext_probe)
struct ExtOptimizerSpec {
  std::string name;                        // NAME of ext:NAME
  std::string command;                     // run with /bin/sh -c
  double timeout_s = kExtDefaultTimeoutS;  // per reply (not in the config: it changes no result)
  std::string reported_name, version;      // from the probe's hello; part of the config
};

// "ext:NAME" -> NAME, "" when the name has no ext: prefix
std::string ext_name_of(const std::string& optimizer);
// NAME: letters, digits, '_', '-', '.'; 1 to 64 characters. UsageError naming it otherwise.
void check_ext_name(const std::string& name);

// Runs the command once with a probe hello ({"protocol": 1, "probe": true}) and returns the spec
// with the name and version the program reports. UsageError "ext:NAME: probe of 'COMMAND'
// failed: REASON" when it does not answer a well-formed hello and exit 0 within the timeout.
ExtOptimizerSpec ext_probe(ExtOptimizerSpec spec);

// An optimizer for one run on env `env` with the run's seed (both sent in the hello).
// config(): {"protocol", "command", "name", "version"}: the run key keeps programs and versions
// apart. A run that breaks the protocol (crash, malformed line, point outside the box, timeout,
// asking after the end, a different version than the probe's) throws std::runtime_error
// "ext:NAME: REASON" (the runner stores the run as 'failed' with it), after killing the program.
std::unique_ptr<Optimizer> make_ext_optimizer(const ExtOptimizerSpec& spec, const std::string& env = "",
                                              std::uint64_t seed = 0);

}  // namespace dsb
