#pragma once
// An env's immutable model, built on first use and then shared: the first thread that needs it
// builds it (std::call_once), every other thread waits for that build and reads the same object.
// Constructing an env therefore costs nothing; listing, grid expansion and resume never build a
// model. lazy_model_builds() counts builds in this process (tests check that metadata paths
// build none).
#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <utility>

namespace dsb {

inline std::atomic<std::int64_t>& lazy_model_build_counter() {
  static std::atomic<std::int64_t> builds{0};
  return builds;
}
inline std::int64_t lazy_model_builds() { return lazy_model_build_counter().load(); }

template <class Model>
class LazyModel {
 public:
  explicit LazyModel(std::function<Model()> build) : build_(std::move(build)) {}
  const Model& get() const {
    std::call_once(once_, [this] {
      model_.emplace(build_());
      built_.store(true, std::memory_order_release);
      lazy_model_build_counter().fetch_add(1);
    });
    return *model_;
  }
  bool built() const { return built_.load(std::memory_order_acquire); }

 private:
  std::function<Model()> build_;
  mutable std::once_flag once_;
  mutable std::optional<Model> model_;
  mutable std::atomic<bool> built_{false};
};

}  // namespace dsb
