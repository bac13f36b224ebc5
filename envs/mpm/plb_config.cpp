#include "envs/mpm/plb_config.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "common/config_fields.hpp"
#include "common/error.hpp"
#include "common/field_check.hpp"
#include "common/regular_file.hpp"
#include "common/rng.hpp"
#include "envs/core/data_dir.hpp"

namespace dsb::mpm {

MpmConfig PlbConfig::default_mpm() {
  MpmConfig c;  // PlasticineLab: 64^3 on the unit cube, dt 1e-4, 19 substeps, gravity (0, -1, 0) x 30
  c.pad = 1;    // its shapes start at y = 0
  return c;
}

PlbConfig plb_config(const std::string& name) {
  const PlbTask* task = find_plb_task(name);
  if (!task) throw UsageError("unknown PlasticineLab task '" + name + "'");
  PlbConfig c;
  c.task = name;
  c.mpm.floor_friction = task->floor_friction;
  // The paper raised the weight of the term that pulls the manipulators towards the plasticine
  // (value not given). Chosen here: 100. At the start the weighted density and SDF terms are 0.9
  // (writer) to 13 (rope, triplemove) per env step, while a manipulator 0.1 away adds 0.01 x the
  // contact weight (measured: docs/plasticinelab.md): with PlasticineLab's 1 the only term whose gradient moves
  // an idle manipulator is about 1% of the loss; with 100 it is of the same order, and it
  // vanishes on contact.
  c.contact_weight = 100.0;
  return c;
}

void PlbConfig::validate() const {
  const FieldCheck check("plb");
  check.require(find_plb_task(task) != nullptr, "task", "unknown task '" + task + "'");
  mpm.validate("plb");
  check.at_least("env_steps", env_steps, 1);
  check.require(segments >= 1 && env_steps % segments == 0, "segments",
                "must divide env_steps (" + std::to_string(env_steps) + "), got " + std::to_string(segments));
  check.require(std::isfinite(softness) && softness >= 0.0, "softness", "must be finite and >= 0");
  check.require(particle_volume > 0.0, "particle_volume", "must be > 0");
  check.require(density > 0.0, "density", "must be > 0");
  for (auto [f, v] :
       {std::pair{"sdf_weight", sdf_weight}, {"density_weight", density_weight}, {"contact_weight", contact_weight}})
    check.require(std::isfinite(v) && v >= 0.0, f, "must be finite and >= 0");
  check.require(observed_particles >= 1, "observed_particles", "must be >= 1");
  // a target file's values are bounded by kMaxTargetMass so that the density term, summed over the
  // steps and nodes, stays far below the largest double (plb_target_file.hpp derives it)
  const double nodes = static_cast<double>(mpm.grid[0]) * mpm.grid[1] * mpm.grid[2];
  check.require(!(static_cast<double>(env_steps) * density_weight * nodes * kMaxTargetMass >
                  0.1 * std::numeric_limits<double>::max()),
                "density_weight",
                "with " + std::to_string(env_steps) + " env steps and " + std::to_string(mpm.grid[0]) +
                    "^3 nodes, a target of kMaxTargetMass per node could overflow the loss");
}

namespace {

// FNV-1a 64 (hex) of a data file's bytes, "missing" when it cannot be read (a target being made)
std::string file_content_hash(const std::string& path) {
  try {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(fnv1a64(read_regular_file("", path))));
    return buf;
  } catch (const UsageError&) {
    return "missing";
  }
}

// the generated target (its file, by name and content, and the motion that made it), or a target
// file by its values' hash (never its path: the same values from anywhere are the same target)
nlohmann::json target_json(const PlbConfig& c, const nlohmann::json& reference) {
  if (!c.target_file) {
    const std::string file = "targets/plb-" + c.task + ".txt.gz";
    nlohmann::json j = {{"file", "data/" + file},
                        {"file_fnv1a64", file_content_hash(data_dir() + "/" + file)},
                        {"reference_motion", reference}};
    // a constructed target (rope's ring) in place of the reference motion's final state
    if (const auto& how = find_plb_task(c.task)->construction; !how.empty()) j["construction"] = how;
    return j;
  }
  return {{"source", "a PlasticineLab-format .npy file (env option target)"},
          {"shape", c.mpm.grid},
          {"values_fnv1a64", c.target_file->hash}};
}

}  // namespace

nlohmann::json PlbConfig::to_json() const {
  const PlbTask& t = *find_plb_task(task);
  nlohmann::json shapes = nlohmann::json::array();
  for (const auto& s : t.shapes) {
    nlohmann::json j = {{"kind", s.kind == PlbShape::Kind::box ? "box" : "sphere"},
                        {"centre", {s.centre.x(), s.centre.y(), s.centre.z()}},
                        {"particles", s.particles}};
    if (s.kind == PlbShape::Kind::box)
      j["size"] = {s.size.x(), s.size.y(), s.size.z()};
    else
      j["radius"] = s.radius;
    shapes.push_back(j);
  }
  nlohmann::json prims = nlohmann::json::array();
  for (const auto& p : t.primitives) prims.push_back(p.to_json());
  nlohmann::json reference = nlohmann::json::array();
  for (const auto& ph : t.reference) reference.push_back({{"steps", ph.steps}, {"actions", ph.actions}});
  nlohmann::json j = fields_json(*this);
  j["material"] = {{"kind", "plastic"},
                   {"youngs_modulus", t.youngs_modulus},
                   {"poisson_ratio", t.poisson_ratio},
                   {"yield_stress", t.yield_stress}};
  j["shapes"] = shapes;
  j["primitives"] = prims;
  j["loss"]["form"] =
      "sum over env steps of sdf_weight sum_I d_I m_I + density_weight sum_I |m_I - t_I| + "
      "contact_weight sum_k (min_p max(sdf_k(x_p), 0))^2";
  j["target"] = target_json(*this, reference);
  j["metric"] = "soft IoU of the final grid mass with the target";
  j["params"] = "5 segments x the manipulators' commands of one env step, each held for env_steps / 5 steps";
  return j;
}

}  // namespace dsb::mpm
