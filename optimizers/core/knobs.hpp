#pragma once
// Knobs: the named scalar fields of an optimizer's config that the command line may set
// (`harness ... --set boleap.sigma0=0.3`). A run made with knobs set stores its resolved config,
// whose hash is part of the run key, so variants of one optimizer never mix in a database.
#include <map>
#include <string>
#include <variant>
#include <vector>

namespace dsb {

// key -> value text, for one optimizer (from --set OPT.KEY=VALUE)
using KnobSettings = std::map<std::string, std::string>;

class KnobTable {
 public:
  explicit KnobTable(std::string owner) : owner_(std::move(owner)) {}
  KnobTable& add(std::string key, double* field);
  KnobTable& add(std::string key, int* field);
  KnobTable& add(std::string key, bool* field);
  // Writes each setting into its field. UsageError "boleap: unknown knob 'foo' (knobs: ...)" or
  // "boleap: knob 'patience' wants an integer, got '2.5'". Range checks stay with the config's
  // validate(), which names the field.
  void apply(const KnobSettings& settings) const;
  std::vector<std::string> keys() const;

 private:
  std::string owner_;
  std::map<std::string, std::variant<double*, int*, bool*>> fields_;
};

// cfg with the settings written into its fields through its knob table (table(cfg), or
// table(owner, cfg) for a table shared by optimizers: gd's and rand-descents')
template <class Config>
Config with_knobs(KnobTable (*table)(Config&), Config cfg, const KnobSettings& settings) {
  table(cfg).apply(settings);
  return cfg;
}
template <class Config>
Config with_knobs(KnobTable (*table)(const std::string&, Config&), const std::string& owner, Config cfg,
                  const KnobSettings& settings) {
  table(owner, cfg).apply(settings);
  return cfg;
}

}  // namespace dsb
