#pragma once
// A config's fields are declared once. Where each stored field is a member stored under its own
// name, the config says
//   DSB_CONFIG_FIELDS(lr, beta1, beta2, eps)
// which defines its member fields(visit), calling visit("lr", lr), visit("beta1", beta1), ... (the
// name is the member's own spelling, so the two cannot drift apart). A config that also stores a
// value derived from a member, or a member under another name, writes fields() itself:
//   template <class Visit> void fields(Visit&& visit) const {
//     DSB_VISIT_FIELDS(visit, population, sigma0);
//     visit("elite", elite_count());
//   }
// fields_json() turns that list into the config's canonical JSON (common/config_hash.hpp hashes
// it). A dotted name nests ("loss.sdf_weight" -> {"loss": {"sdf_weight": ...}}), and a value with a
// to_json() member (a nested config) is stored as its JSON. The JSON is an object with sorted keys,
// so the order of the list does not change the text.
#include <string>

#include <nlohmann/json.hpp>

// DSB_VISIT_FIELDS(fn, a, b, ...) -> fn("a", a); fn("b", b); ... for up to 64 members: each step
// defers the next one behind an empty pair of parentheses, and DSB_FIELDS_RESCAN scans the text
// 64 times, one step a scan (the C++20 __VA_OPT__ form of a preprocessor for-each)
#define DSB_FIELDS_PARENS ()
#define DSB_FIELDS_RESCAN(...) \
  DSB_FIELDS_RESCAN16(DSB_FIELDS_RESCAN16(DSB_FIELDS_RESCAN16(DSB_FIELDS_RESCAN16(__VA_ARGS__))))
#define DSB_FIELDS_RESCAN16(...) \
  DSB_FIELDS_RESCAN4(DSB_FIELDS_RESCAN4(DSB_FIELDS_RESCAN4(DSB_FIELDS_RESCAN4(__VA_ARGS__))))
#define DSB_FIELDS_RESCAN4(...) \
  DSB_FIELDS_RESCAN1(DSB_FIELDS_RESCAN1(DSB_FIELDS_RESCAN1(DSB_FIELDS_RESCAN1(__VA_ARGS__))))
#define DSB_FIELDS_RESCAN1(...) __VA_ARGS__
#define DSB_VISIT_FIELDS(fn, ...) __VA_OPT__(DSB_FIELDS_RESCAN(DSB_VISIT_FIELDS_STEP(fn, __VA_ARGS__)))
#define DSB_VISIT_FIELDS_STEP(fn, member, ...) \
  fn(#member, member);                         \
  __VA_OPT__(DSB_VISIT_FIELDS_NEXT DSB_FIELDS_PARENS(fn, __VA_ARGS__))
#define DSB_VISIT_FIELDS_NEXT() DSB_VISIT_FIELDS_STEP

// the member fields() of a config whose stored fields are exactly these members, by their names
#define DSB_CONFIG_FIELDS(...)           \
  template <class Visit>                 \
  void fields(Visit&& visit) const {     \
    DSB_VISIT_FIELDS(visit, __VA_ARGS__) \
  }

namespace dsb {

// {"a.b": v} -> j["a"]["b"] = v, a nested config as its to_json()
template <class Config>
nlohmann::json fields_json(const Config& config) {
  nlohmann::json j = nlohmann::json::object();
  config.fields([&j](const std::string& name, const auto& value) {
    nlohmann::json* slot = &j;
    std::string::size_type from = 0;
    for (auto dot = name.find('.'); dot != std::string::npos; dot = name.find('.', from)) {
      slot = &(*slot)[name.substr(from, dot - from)];
      from = dot + 1;
    }
    const std::string key = name.substr(from);
    if constexpr (requires { value.to_json(); })
      (*slot)[key] = value.to_json();
    else
      (*slot)[key] = value;
  });
  return j;
}

}  // namespace dsb
