#include "reference/events.hpp"

#include <algorithm>

namespace dsb::reference {

ContactEvents contact_events(const Rollout& r, const Eigen::Vector3d& gravity, double dt) {
  ContactEvents e;
  const int steps = static_cast<int>(r.velocity.size()) - 1;
  // contact steps: the velocity change is not gravity's alone
  std::vector<int> contact;
  for (int t = 0; t < steps; ++t)
    if ((r.velocity[t + 1] - r.velocity[t] - dt * gravity).norm() > kContactDv) contact.push_back(t);
  if (contact.empty()) return e;
  e.first_impact = contact.front();
  // episodes: runs of contact steps, gaps of up to kEpisodeGap free steps merged
  std::size_t i = 0;
  while (i < contact.size()) {
    std::size_t j = i;
    while (j + 1 < contact.size() && contact[j + 1] - contact[j] <= kEpisodeGap + 1) ++j;
    const int a = contact[i], b = contact[j] + 1;  // states a .. b
    // the velocity change the contact made (gravity's share removed)
    const Eigen::Vector3d dv = r.velocity[b] - r.velocity[a] - (b - a) * dt * gravity;
    ++e.episodes;
    e.episode_starts.push_back(a);
    e.episode_ends.push_back(b);
    e.episode_bounces.push_back(dv.norm() > kBounceDv);
    e.clearest_graze = std::min(e.clearest_graze, dv.norm());
    if (dv.norm() > kBounceDv) ++e.bounces;
    i = j + 1;
  }
  return e;
}

}  // namespace dsb::reference
