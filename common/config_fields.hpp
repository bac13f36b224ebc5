#pragma once
// A config's fields are declared once, in its member
//   template <class Visit> void fields(Visit&& visit) const { visit("name", member); ... }
// which names each stored field (or a value derived from one) once; fields_json() turns that list
// into the config's canonical JSON (common/config_hash.hpp hashes it). A dotted name nests
// ("loss.sdf_weight" -> {"loss": {"sdf_weight": ...}}), and a value with a to_json() member (a
// nested config) is stored as its JSON. The JSON is an object with sorted keys, so the order of
// the list does not change the text.
#include <string>

#include <nlohmann/json.hpp>

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
