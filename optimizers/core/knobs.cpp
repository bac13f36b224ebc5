#include "optimizers/core/knobs.hpp"

#include <charconv>
#include <cmath>

#include "common/error.hpp"

namespace dsb {

KnobTable& KnobTable::add(std::string key, double* field) {
  fields_[std::move(key)] = field;
  return *this;
}
KnobTable& KnobTable::add(std::string key, int* field) {
  fields_[std::move(key)] = field;
  return *this;
}
KnobTable& KnobTable::add(std::string key, bool* field) {
  fields_[std::move(key)] = field;
  return *this;
}

std::vector<std::string> KnobTable::keys() const {
  std::vector<std::string> out;
  for (const auto& [k, f] : fields_) out.push_back(k);
  return out;
}

void KnobTable::apply(const KnobSettings& settings) const {
  for (const auto& [key, text] : settings) {
    const auto it = fields_.find(key);
    if (it == fields_.end()) {
      std::string known;
      for (const auto& k : keys()) known += (known.empty() ? "" : ", ") + k;
      throw UsageError(owner_ + ": unknown knob '" + key + "' (knobs: " + known + ")");
    }
    const char* first = text.data();
    const char* last = first + text.size();
    auto bad = [&](const char* want) {
      return UsageError(owner_ + ": knob '" + key + "' wants " + want + ", got '" + text + "'");
    };
    if (auto* d = std::get_if<double*>(&it->second)) {
      double v = 0.0;
      const auto r = std::from_chars(first, last, v);
      if (r.ec != std::errc() || r.ptr != last || !std::isfinite(v)) throw bad("a finite number");
      **d = v;
    } else if (auto* i = std::get_if<int*>(&it->second)) {
      int v = 0;
      const auto r = std::from_chars(first, last, v);
      if (r.ec != std::errc() || r.ptr != last) throw bad("an integer");
      **i = v;
    } else {
      bool* b = std::get<bool*>(it->second);
      if (text == "true" || text == "1")
        *b = true;
      else if (text == "false" || text == "0")
        *b = false;
      else
        throw bad("true or false");
    }
  }
}

}  // namespace dsb
