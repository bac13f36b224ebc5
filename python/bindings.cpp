// The Python module diffsim_bench: our simulators driven from a user's own loop.
//
//   import diffsim_bench as dsb
//   dsb.envs()                                  # [{name, dim, differentiable, rl, ...}, ...]
//   env = dsb.make("cartpole1", threads=1)      # the registry's env (its model is shared)
//   env = dsb.make("plb-pinch", target="Pinch3D-v1.npy")  # with env options (--set ENV.KEY=VALUE)
//   env.loss(x); env.loss_and_grad(x)           # x in [-1, 1]^dim -> float, (float, ndarray)
//   rl = env.rl(); rl.reset(); rl.observe(); rl.step(a); rl.done(); rl.final_loss()
//
// A rollout runs exactly as `harness eval` runs it (the registry's env, its Workspace, a
// ThreadTeam), so the numbers are the same bits; a team of any size gives the same bits too.
// The GIL is released while a rollout or an RL step runs, so other Python threads go on (and
// two Env objects roll out in parallel). One Env or RL view is used by one rollout at a time:
// concurrent calls on the same object wait for each other.
// Errors: bad input raises ValueError naming the value (a wrong length names the length);
// a failed rollout (the simulation blew up) returns nan, as the harness records it.
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "common/error.hpp"
#include "git_sha.hpp"  // generated: DSB_GIT_SHA
#include "common/shown_value.hpp"
#include "common/thread_team.hpp"
#include "common/unit_box.hpp"
#include "common/usable_cpus.hpp"
#include "envs/core/env.hpp"
#include "envs/registry.hpp"

namespace py = pybind11;

namespace dsb::python {
namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::string repr(double v) { return py::repr(py::float_(v)).cast<std::string>(); }

// a Python value as a message shows it: its repr(), control characters escaped, at most 80 characters
std::string shown(const py::handle& v) {
  std::string r;
  try {
    r = py::repr(v).cast<std::string>();
  } catch (const py::error_already_set&) {
    r = "<unprintable>";
  }
  if (r.size() > 80) r = r.substr(0, 77) + "...";
  return shown_value(r);
}

std::string type_name(const py::handle& v) { return Py_TYPE(v.ptr())->tp_name; }

bool is_numpy(const py::handle& v, const char* type) {
  return py::isinstance(v, py::module_::import("numpy").attr(type));
}

// Empty when v is a real number: a Python int or float, a numpy integer or floating scalar, or a
// 0-d numpy array of one; else why not ("a str", "None", "a bool"). A bool (Python's or numpy's) is
// True or False, not a number, and a str is text even when it reads as one.
std::string not_a_real_number(const py::handle& v) {
  if (PyBool_Check(v.ptr())) return "a bool";                      // before int: bool is an int in Python
  if (PyLong_Check(v.ptr()) || PyFloat_Check(v.ptr())) return "";  // numpy's float64 is a float
  if (v.is_none()) return "None";
  if (is_numpy(v, "bool_")) return "a bool";
  if (is_numpy(v, "integer") || is_numpy(v, "floating")) return "";
  if (py::isinstance<py::array>(v)) {
    const auto a = py::reinterpret_borrow<py::array>(v);
    const char kind = a.dtype().kind();
    if (a.ndim() == 0 && (kind == 'f' || kind == 'i' || kind == 'u')) return "";
  }
  return "a " + type_name(v);
}

// A 1-D numpy array or sequence of real numbers (not_a_real_number) as doubles, copied: the
// caller's buffer may change while the GIL is released. `what` names the argument in messages.
// TypeError for anything else, naming the value that is not a number and its position.
std::vector<double> to_vector(const py::object& obj, const char* what) {
  const std::string w = what;
  if (py::isinstance<py::array>(obj)) {
    const auto a = py::reinterpret_borrow<py::array>(obj);
    if (a.ndim() != 1) throw py::value_error(w + " must be 1-D, got " + std::to_string(a.ndim()) + " dimensions");
    const char kind = a.dtype().kind();
    if (kind == 'f' || kind == 'i' || kind == 'u') {
      const Array d = Array::ensure(obj);
      if (!d) throw py::error_already_set();
      return std::vector<double>(d.data(), d.data() + d.size());
    }
    if (kind != 'O')  // bool, complex, text, dates: an object array's items are checked one by one below
      throw py::type_error(w + " must hold real numbers, got a numpy array of dtype " +
                           shown_value(py::str(a.dtype()).cast<std::string>()));
  } else if (PyUnicode_Check(obj.ptr()) || PyBytes_Check(obj.ptr()) || PyByteArray_Check(obj.ptr()) ||
             !PySequence_Check(obj.ptr())) {
    throw py::type_error(w + " must be a 1-D numpy array or sequence of numbers, got " + type_name(obj) + " " +
                         shown(obj));
  }
  const py::sequence seq = py::reinterpret_borrow<py::sequence>(obj);
  std::vector<double> out;
  out.reserve(seq.size());
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const py::object v = seq[i];
    const auto at = [&] { return ": value " + shown(v) + " at position " + std::to_string(i); };  // errors only
    const bool nested = py::isinstance<py::array>(v)
        ? py::reinterpret_borrow<py::array>(v).ndim() > 0
        : PySequence_Check(v.ptr()) && !PyUnicode_Check(v.ptr()) && !PyBytes_Check(v.ptr());
    if (nested) throw py::value_error(w + " must be 1-D" + at() + " is a " + type_name(v));
    if (const std::string why = not_a_real_number(v); !why.empty())
      throw py::type_error(w + at() + " is " + why + ", not a real number");
    const double d = PyFloat_AsDouble(v.ptr());
    if (d == -1.0 && PyErr_Occurred()) {
      PyErr_Clear();
      throw py::value_error(w + at() + " is too large for a double");
    }
    out.push_back(d);
  }
  return out;
}

// x for a rollout of `env`: dim values inside [-1, 1] (the wording of `harness eval`)
std::vector<double> checked_point(const Env& env, const py::object& obj) {
  auto x = to_vector(obj, "x");
  if (static_cast<int>(x.size()) != env.dim())
    throw py::value_error("x has " + std::to_string(x.size()) + " values, env '" + env.name() + "' needs " +
                          std::to_string(env.dim()));
  if (const auto i = first_outside_box(x); i >= 0)  // NaN fails too
    throw py::value_error("x: value " + repr(x[i]) + " at position " + std::to_string(i) + " is outside [-1, 1]");
  return x;
}

py::object json_to_python(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

py::dict info_dict(const EnvInfo& info, const std::string& description) {
  py::dict d;
  d["name"] = info.name;
  d["dim"] = info.dim;
  d["differentiable"] = info.differentiable;
  d["rl"] = info.rl;
  d["description"] = description;
  d["threaded"] = info.threaded;
  d["cost_hint_s"] = info.cost_hint_s;
  d["metric"] = info.metric.empty() ? py::object(py::none()) : py::object(py::str(info.metric));
  return d;
}

// the description `harness list` shows for an env of this family
std::string family_description(const EnvFamily& family, const std::string& name) {
  return family.pattern == name ? family.description : family.pattern + ": " + family.description;
}

// the family that knows the name (constructing an env is cheap: metadata only)
std::string description_of(const std::string& name) {
  for (const auto& family : env_families())
    if (family.try_make(name)) return family_description(family, name);
  return "";
}

// every env of the `--all` grid, as `harness list` shows them (metadata only: builds no model)
py::list list_envs() {
  py::list out;
  for (const auto& family : env_families())
    for (const auto& name : family.grid_names)
      out.append(info_dict(shared_env(name)->info(), family_description(family, name)));
  return out;
}

// whether option `key` of env `name` names a file (EnvOptionInfo::path); false when the env or the
// option is unknown (make then reports it as the harness does)
bool option_is_path(const std::string& name, const std::string& key) {
  for (const auto& family : env_families()) {
    if (!family.try_make(name)) continue;
    for (const auto& o : family.options)
      if (o.key == key) return o.path;
    return false;
  }
  return false;
}

// An env option's value as `harness --set ENV.KEY=VALUE` takes it. A path option takes what open()
// takes: a str, bytes or os.PathLike, as the file name's bytes (os.fsencode: a bytes path is the
// name itself, never the text "b'...'"); any other option a str or a real number. TypeError
// naming the value otherwise (`target=5` is no path).
std::string option_text(const std::string& name, const std::string& key, const py::handle& value) {
  const std::string label = name + "." + key;
  if (option_is_path(name, key)) {
    const py::module_ os = py::module_::import("os");
    const bool path_like =
        PyUnicode_Check(value.ptr()) || PyBytes_Check(value.ptr()) || py::isinstance(value, os.attr("PathLike"));
    if (!path_like)
      throw py::type_error(label + " must be a path (str, bytes or os.PathLike), got " + type_name(value) + " " +
                           shown(value));
    const std::string bytes = os.attr("fsencode")(value).cast<std::string>();
    if (bytes.find('\0') != std::string::npos)
      throw py::value_error(label + ": the path " + shown(value) + " holds a null byte");
    return bytes;
  }
  if (PyUnicode_Check(value.ptr())) return value.cast<std::string>();
  if (not_a_real_number(value).empty()) return py::str(value).cast<std::string>();
  throw py::type_error(label + " must be a str or a number, got " + type_name(value) + " " + shown(value));
}

// The RL view (reset / observe / step) of one env; holds the env so its model outlives the view.
class PyRl {
 public:
  explicit PyRl(std::shared_ptr<const Env> env) : env_(std::move(env)) {
    py::gil_scoped_release release;  // may build the model
    rl_ = env_->make_rl();
  }
  int observation_dim() const { return rl_->observation_dim(); }
  int action_dim() const { return rl_->action_dim(); }
  int horizon() const { return rl_->horizon(); }
  int action_repeat() const { return rl_->action_repeat(); }

  void reset() {
    py::gil_scoped_release release;
    std::lock_guard lock(mutex_);
    rl_->reset();
  }
  Array observe() {
    std::vector<double> o;
    {
      py::gil_scoped_release release;
      std::lock_guard lock(mutex_);
      o = rl_->observe();
    }
    return Array(static_cast<py::ssize_t>(o.size()), o.data());
  }
  // one step; actions beyond [-1, 1] are clipped by the env, as for the harness's RL optimizers
  void step(const py::object& obj) {
    const auto a = to_vector(obj, "action");
    if (static_cast<int>(a.size()) != rl_->action_dim())
      throw py::value_error("action has " + std::to_string(a.size()) + " values, env '" + env_->name() + "' needs " +
                            std::to_string(rl_->action_dim()));
    for (std::size_t i = 0; i < a.size(); ++i)
      if (!std::isfinite(a[i]))
        throw py::value_error("action: value " + repr(a[i]) + " at position " + std::to_string(i) +
                              " is not a finite number");
    bool was_done = false;
    {
      py::gil_scoped_release release;
      std::lock_guard lock(mutex_);
      was_done = rl_->done();
      if (!was_done) rl_->step(a);
    }
    if (was_done) throw std::runtime_error("step: the episode of env '" + env_->name() + "' is done; call reset()");
  }
  bool done() {
    py::gil_scoped_release release;
    std::lock_guard lock(mutex_);
    return rl_->done();
  }
  // the episode's loss once done(): loss(x) of the same actions; nan when the simulation blew up
  double final_loss() {
    py::gil_scoped_release release;
    std::lock_guard lock(mutex_);
    if (!rl_->done()) throw std::runtime_error("final_loss: the episode of env '" + env_->name() + "' is not done");
    return rl_->final_loss();
  }

 private:
  std::shared_ptr<const Env> env_;
  std::unique_ptr<RlEnv> rl_;
  std::mutex mutex_;
};

// One env for a user's loop: the registry's shared model, a team of `threads`, one workspace.
class PyEnv {
 public:
  PyEnv(const std::string& name, int threads, const EnvOptions& options) {
    if (threads < 1) throw py::value_error("threads must be >= 1, got " + std::to_string(threads));
    // the harness's --threads cap: more threads than CPUs only slow a rollout down
    if (threads > usable_cpus())
      throw py::value_error("threads " + std::to_string(threads) + " is more than the " +
                            std::to_string(usable_cpus()) +
                            " CPUs this process may use (the cap: more threads than CPUs only slow a rollout down; "
                            "results are the same for any count)");
    env_ = shared_env(name, options);  // metadata only: the model is built on the first rollout
    description_ = description_of(name);
    team_ = std::make_unique<ThreadTeam>(threads);
  }
  const std::string& name() const { return env_->name(); }
  int dim() const { return env_->dim(); }
  bool differentiable() const { return env_->differentiable(); }
  bool supports_rl() const { return env_->supports_rl(); }
  int threads() const { return team_->size(); }
  py::object metric() const {
    const auto& m = env_->info().metric;
    return m.empty() ? py::object(py::none()) : py::object(py::str(m));
  }
  py::dict info() const { return info_dict(env_->info(), description_); }
  py::object config() const { return json_to_python(env_->config()); }

  double loss(const py::object& obj) {
    const auto x = checked_point(*env_, obj);
    py::gil_scoped_release release;
    std::lock_guard lock(mutex_);
    return env_->loss(x, workspace(), *team_);
  }
  py::tuple loss_and_grad(const py::object& obj) {
    const auto x = checked_point(*env_, obj);
    if (!env_->differentiable())
      throw py::value_error("loss_and_grad: env '" + env_->name() + "' is not differentiable");
    Array grad(env_->dim());
    double* g = grad.mutable_data();
    double loss = 0.0;
    {
      py::gil_scoped_release release;
      std::lock_guard lock(mutex_);
      loss = env_->loss_and_grad(x, std::span<double>(g, static_cast<std::size_t>(env_->dim())), workspace(), *team_);
    }
    return py::make_tuple(loss, grad);
  }
  // the env's second metric (info's "metric") of the last rollout; None when the env has none
  py::object last_metric() {
    if (env_->info().metric.empty()) return py::none();
    double v = std::nan("");
    {
      py::gil_scoped_release release;
      std::lock_guard lock(mutex_);
      if (ws_) v = env_->episode_metric(*ws_);
    }
    return py::float_(v);
  }
  std::unique_ptr<PyRl> rl() const {
    if (!env_->supports_rl()) throw py::value_error("rl: env '" + env_->name() + "' has no RL view");
    return std::make_unique<PyRl>(env_);
  }
  std::string repr() const {
    return "<diffsim_bench.Env '" + env_->name() + "' dim=" + std::to_string(env_->dim()) +
        " threads=" + std::to_string(team_->size()) + ">";
  }

 private:
  // made on the first rollout (it builds the model), then reused; under mutex_
  Workspace& workspace() {
    if (!ws_) ws_ = env_->make_workspace();
    return *ws_;
  }
  std::shared_ptr<const Env> env_;
  std::string description_;
  std::unique_ptr<ThreadTeam> team_;
  std::unique_ptr<Workspace> ws_;
  std::mutex mutex_;
};

}  // namespace
}  // namespace dsb::python

PYBIND11_MODULE(diffsim_bench, m) {
  using namespace dsb::python;
  m.doc() = "diffsim-bench's differentiable simulators: envs(), make(name, threads=1) -> Env";
  m.attr("__version__") = DSB_VERSION;
  m.attr("git_sha") = DSB_GIT_SHA;

  // bad user input from the library (unknown env name, a bad name parameter) -> ValueError
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const dsb::UsageError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });

  py::class_<PyRl>(m, "RlView", "Per-step interface of an env: reset(), observe(), step(action), done(), final_loss()")
      .def_property_readonly("observation_dim", &PyRl::observation_dim)
      .def_property_readonly("action_dim", &PyRl::action_dim)
      .def_property_readonly("horizon", &PyRl::horizon, "steps per episode")
      .def_property_readonly("action_repeat", &PyRl::action_repeat,
                             "env steps an RL agent's action is held for by the harness's RL optimizers")
      .def("reset", &PyRl::reset)
      .def("observe", &PyRl::observe, "the observation (observation_dim numbers)")
      .def("step", &PyRl::step, py::arg("action"),
           "one env step with action (action_dim numbers; values beyond [-1, 1] are clipped by the env). "
           "Releases the GIL. RuntimeError once done().")
      .def("done", &PyRl::done)
      .def("final_loss", &PyRl::final_loss,
           "the episode's loss once done(): loss(x) for the same actions; nan when it blew up");

  py::class_<PyEnv>(m, "Env", "An env: loss(x), loss_and_grad(x) over x in [-1, 1]^dim, and rl()")
      .def_property_readonly("name", &PyEnv::name)
      .def_property_readonly("dim", &PyEnv::dim)
      .def_property_readonly("differentiable", &PyEnv::differentiable)
      .def_property_readonly("supports_rl", &PyEnv::supports_rl, "whether rl() gives a per-step view")
      .def_property_readonly("threads", &PyEnv::threads)
      .def_property_readonly("metric", &PyEnv::metric, "name of the env's second metric, or None")
      .def_property_readonly("info", &PyEnv::info, "the env's metadata as a dict (as envs() has it)")
      .def_property_readonly("config", &PyEnv::config,
                             "the resolved config (every constant that changes the loss) as a dict")
      .def("loss", &PyEnv::loss, py::arg("x"),
           "Loss at x (dim numbers in [-1, 1]); nan when the simulation blew up. Releases the GIL.")
      .def("loss_and_grad", &PyEnv::loss_and_grad, py::arg("x"),
           "(loss, dLoss/dx as a numpy array) at x, in normalized units; nan when the simulation blew up. "
           "Releases the GIL.")
      .def("last_metric", &PyEnv::last_metric,
           "the second metric (see metric) of this Env's last rollout; None when the env has none")
      .def("rl", &PyEnv::rl, "a new per-step view (reset/observe/step) over the same dynamics")
      .def("__repr__", &PyEnv::repr);

  m.def("envs", &list_envs,
        "Every env of the harness's --all grid (as `harness list`): a list of dicts with name, dim, "
        "differentiable, rl, description, threaded, cost_hint_s and metric. Builds no model.");
  m.def(
      "make",
      [](const std::string& name, const py::object& threads, const py::kwargs& kwargs) {
        // each keyword is an env option, its value as text (option_text)
        dsb::EnvOptions options;
        for (const auto& [key, value] : kwargs) {
          const std::string k = key.cast<std::string>();
          options[k] = option_text(name, k, value);
        }
        if (!PyLong_Check(threads.ptr()) || PyBool_Check(threads.ptr()))
          throw py::type_error("threads must be an int, got " + type_name(threads) + " " + shown(threads));
        int overflow = 0;
        const long long t = PyLong_AsLongLongAndOverflow(threads.ptr(), &overflow);
        const int n = overflow != 0 ? (overflow > 0 ? INT_MAX : INT_MIN)
                                    : static_cast<int>(std::clamp<long long>(t, INT_MIN, INT_MAX));
        return std::make_unique<PyEnv>(name, n, options);
      },
      py::arg("name"), py::arg("threads") = 1,
      "The env NAME (any name the harness takes, e.g. 'sphere-3' or 'fluid-h5') with a team of THREADS "
      "threads inside each rollout (same results for every THREADS; at most the CPUs this process may use). Cheap: the model is built on the first "
      "rollout and shared by every Env of that name and options. Keywords are the env's options, as "
      "`harness --set ENV.KEY=VALUE` takes them (`harness list` shows them), e.g. "
      "make('plb-pinch', target='Pinch3D-v1.npy'). ValueError for an unknown name, an option the env does not "
      "take, or a bad option value (e.g. an unreadable target file).");
}
