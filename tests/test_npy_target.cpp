// PlasticineLab-format target files (`--set plb-NAME.target=FILE.npy`): our .npy reader against
// files Debian's numpy writes (float64, float32, versions 1 to 3, and every kind of bad file), the
// target's place on our nodes and its hash, a loaded copy of our own target giving the built-in
// target's loss bit for bit, env config hashes, env options in the registry, and the harness's
// commands (eval, a grid, plan, slurm, list) and scripts/plb-targets.sh compare end to end.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/config_hash.hpp"
#include "common/error.hpp"
#include "common/rng.hpp"
#include "envs/mpm/npy_array.hpp"
#include "envs/mpm/plb_env.hpp"
#include "envs/mpm/plb_model.hpp"
#include "envs/mpm/plb_target_file.hpp"
#include "envs/mpm/target_grid.hpp"
#include "envs/registry.hpp"
#include "support/harness_process.hpp"

namespace dsb {
namespace {

namespace fs = std::filesystem;
using mpm::NodeGrid;
using mpm::read_npy;
using mpm::read_plb_target;

// Every file the tests read, written once per run of this binary: numpy's own files from a
// small seeded array and 64^3 target grids, the bad files made from them, and our table and
// pinch targets saved by np.save from their raw values.
const char* kMakeFiles = R"PY(
import sys
import numpy as np
d = sys.argv[1]
rng = np.random.default_rng(0)

def save_bytes(name, data):
    with open(d + '/' + name, 'wb') as f:
        f.write(data)

small = rng.uniform(-1, 1, (2, 3, 4))
np.save(d + '/small_f8.npy', small)
np.save(d + '/small_f4.npy', small.astype('<f4'))
for v in (2, 3):
    with open(d + '/small_v%d.npy' % v, 'wb') as f:
        np.lib.format.write_array(f, small, version=(v, 0))
np.save(d + '/vector.npy', np.array([1.5, -2.25, 3.0]))
np.save(d + '/scalar.npy', np.float64(0.1))
with open(d + '/small_f8.txt', 'w') as f:
    f.write('\n'.join(repr(float(v)) for v in small.ravel()))
with open(d + '/small_f4.txt', 'w') as f:
    f.write('\n'.join(repr(float(v)) for v in small.astype('<f4').astype('<f8').ravel()))

np.save(d + '/fortran.npy', np.asfortranarray(small))
np.save(d + '/int32.npy', small.astype('<i4'))
np.save(d + '/big_endian.npy', small.astype('>f8'))
np.save(d + '/half.npy', small.astype('<f2'))
np.save(d + '/structured.npy', np.zeros(3, dtype=[('a', '<f8'), ('b', '<f8')]))
whole = open(d + '/small_f8.npy', 'rb').read()
save_bytes('truncated.npy', whole[:-5])
save_bytes('truncated_header.npy', whole[:40])
save_bytes('trailing.npy', whole + bytes(8))
v4 = bytearray(whole)
v4[6] = 4
save_bytes('version4.npy', bytes(v4))
save_bytes('not_npy.npy', b'PK\x03\x04 a zip file, not an array')

t = np.zeros((64, 64, 64))
t[20:44, 0:10, 20:44] = 1e-3 * rng.uniform(0.5, 1.5, (24, 10, 24))
np.save(d + '/target_a.npy', t)
t2 = t.copy()
t2[30, 5, 30] += 1e-6
np.save(d + '/target_b.npy', t2)
np.save(d + '/target_a_f4.npy', t.astype('<f4'))
np.save(d + '/target_a_f4_as_f8.npy', t.astype('<f4').astype('<f8'))
np.save(d + '/target_2d.npy', np.zeros((64, 64)))
np.save(d + '/target_65.npy', np.zeros((65, 64, 64)))
tn = t.copy()
tn[1, 2, 3] = np.nan
np.save(d + '/target_nan.npy', tn)
np.save(d + '/target_fortran.npy', np.asfortranarray(t))
whole = open(d + '/target_a.npy', 'rb').read()
save_bytes('target_truncated.npy', whole[:len(whole) // 2])

# not mass grids: a cell at -5, every cell at -1, a cell just below -1e-4, no mass, a cell at
# 1.7e308; and grids that are: PlasticineLab-like tiny negatives (-2.3e-5 and the bound -1e-4, far
# from the plasticine, and a copy with them positive), every cell at the upper bound 1e299
for name, value in (('negative', -5.0), ('below_tolerance', -1.0001e-4), ('huge', 1.7e308)):
    tb = t.copy()
    tb[5, 6, 7] = value
    np.save(d + '/target_%s.npy' % name, tb)
np.save(d + '/target_all_negative.npy', -np.ones((64, 64, 64)))
np.save(d + '/target_zero.npy', np.zeros((64, 64, 64)))
for name, sign in (('tiny_negative', -1.0), ('tiny_positive', 1.0)):
    tb = t.copy()
    tb[60, 60, 60] = sign * 2.3e-5
    tb[62, 1, 3] = sign * 1e-4
    np.save(d + '/target_%s.npy' % name, tb)
np.save(d + '/target_at_bound.npy', np.full((64, 64, 64), 1e299))

# headers by Python's literal rules, each with numpy's own verdict (np.load) beside it
import struct
verdicts = []
def with_header(name, header, major=1, values=np.zeros(2)):
    h = header.encode('latin1')
    length = struct.pack('<H', len(h)) if major == 1 else struct.pack('<I', len(h))
    save_bytes(name, b'\x93NUMPY' + bytes([major, 0]) + length + h + values.astype('<f8').tobytes())
    try:
        np.load(d + '/' + name)
        verdicts.append(name + ' accepts')
    except Exception:
        verdicts.append(name + ' refuses')
head = "{'descr': '<f8', 'fortran_order': False, 'shape': %s, }\n"
with_header('h_plain.npy', head % '(2,)')
with_header('h_leading_zero.npy', head % '(02,)')
with_header('h_zeros.npy', head % '(00,)', values=np.zeros(0))
with_header('h_list.npy', head % '[2]')
with_header('h_parenthesised_int.npy', head % '(2)')
with_header('h_nested_parens.npy', head % '((2,))')
with_header('h_spaced.npy', head % '( 2 , )')
with_header('h_long_v1.npy', head % '(2L,)')
with_header('h_long_v2.npy', head % '(2L,)', major=2)
with_header('h_long_v3.npy', head % '(2L,)', major=3)
with_header('h_leading_space.npy', ' ' + head % '(2,)')
with_header('h_escape.npy', "{'descr': '<f8\x1b[2J', 'fortran_order': False, 'shape': (2,), }\n")
with_header('target_leading_zero.npy', head % '(064, 64, 64)', values=t)
with open(d + '/numpy_verdicts.txt', 'w') as f:
    f.write('\n'.join(verdicts) + '\n')

for name in ('table', 'pinch'):
    ours = np.fromfile(d + '/ours_%s.bin' % name, dtype='<f8').reshape(64, 64, 64)
    np.save(d + '/ours_%s.npy' % name, ours)
    np.save(d + '/ours_%s_v2.npy' % name, ours)
)PY";

std::vector<double> read_numbers(const fs::path& p) {
  std::ifstream in(p);
  std::vector<double> v;
  std::string line;
  while (std::getline(in, line)) v.push_back(std::strtod(line.c_str(), nullptr));
  return v;
}

// our stored target of a task at PlasticineLab's nodes, as raw little-endian doubles
void write_raw_target(const std::string& task, const fs::path& out) {
  const auto cfg = mpm::plb_config(task);
  const auto values = mpm::plb_node_values(mpm::read_grid_gz(mpm::plb_target_path(task)), cfg.mpm);
  std::ofstream f(out, std::ios::binary);
  f.write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(values.size() * sizeof(double)));
}

class NpyTarget : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("dsb_npy_target_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    write_raw_target("table", dir_ / "ours_table.bin");
    write_raw_target("pinch", dir_ / "ours_pinch.bin");
    std::ofstream(dir_ / "make_files.py") << kMakeFiles;
    const std::string cmd = "/usr/bin/python3 " + (dir_ / "make_files.py").string() + " " + dir_.string();
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static std::string file(const std::string& name) { return (dir_ / name).string(); }

  // the one-line message of a read that must fail, "" when it does not
  template <class Read>
  static std::string refusal(Read&& read) {
    try {
      read();
    } catch (const UsageError& e) {
      return e.what();
    }
    return "";
  }

  // a refusal's message starts with the path of the file `name` and says `problem`
  static void expect_names_file_and_problem(const std::string& why, const std::string& name,
                                            const std::string& problem) {
    EXPECT_EQ(why.rfind(file(name) + ": ", 0), 0u) << why;
    EXPECT_NE(why.find(problem), std::string::npos) << why;
  }

  static fs::path dir_;
};

fs::path NpyTarget::dir_;

TEST_F(NpyTarget, ReadsNumpysFloat64AndFloat32InEveryVersion) {
  const auto f8 = read_numbers(dir_ / "small_f8.txt"), f4 = read_numbers(dir_ / "small_f4.txt");
  ASSERT_EQ(f8.size(), 24u);
  for (const char* name : {"small_f8.npy", "small_v2.npy", "small_v3.npy"}) {
    SCOPED_TRACE(name);
    const auto a = read_npy(file(name));
    EXPECT_EQ(a.shape, (std::vector<std::size_t>{2, 3, 4}));
    EXPECT_EQ(a.dtype, "<f8");
    EXPECT_EQ(a.values, f8);  // bit for bit: repr() round-trips
  }
  const auto a = read_npy(file("small_f4.npy"));
  EXPECT_EQ(a.dtype, "<f4");
  EXPECT_EQ(a.values, f4);  // each float as the double of its value
  EXPECT_NE(a.values, f8);  // and not the float64 ones
  EXPECT_EQ(read_npy(file("vector.npy")).values, (std::vector<double>{1.5, -2.25, 3.0}));
  EXPECT_EQ(read_npy(file("vector.npy")).shape, std::vector<std::size_t>{3});
  const auto s = read_npy(file("scalar.npy"));
  EXPECT_TRUE(s.shape.empty());
  EXPECT_EQ(s.values, std::vector<double>{0.1});
  EXPECT_EQ(mpm::npy_shape_text({64, 64, 64}), "(64, 64, 64)");
  EXPECT_EQ(mpm::npy_shape_text({3}), "(3,)");
  EXPECT_EQ(mpm::npy_shape_text({}), "()");
}

TEST_F(NpyTarget, RefusesBadFilesWithOneLineNamingFileAndProblem) {
  const std::pair<const char*, const char*> cases[] = {
      {"fortran.npy", "Fortran order (fortran_order: True) is not read"},
      {"int32.npy", "dtype '<i4' is not read"},
      {"big_endian.npy", "dtype '>f8' is not read"},
      {"half.npy", "dtype '<f2' is not read"},
      {"structured.npy", "dtype is a structured type"},
      {"truncated.npy", "truncated data: 187 bytes, shape (2, 3, 4) of '<f8' needs 192"},
      {"truncated_header.npy", "truncated header"},
      {"trailing.npy", "8 bytes after the data"},
      {"version4.npy", "unsupported .npy version 4.0"},
      {"not_npy.npy", "not a .npy file"},
      {"missing.npy", "cannot open: No such file or directory"},
  };
  for (const auto& [name, problem] : cases) {
    SCOPED_TRACE(name);
    const std::string why = refusal([&] { read_npy(file(name)); });
    expect_names_file_and_problem(why, name, problem);
    EXPECT_EQ(why.find('\n'), std::string::npos) << why;
  }
  EXPECT_NE(refusal([&] { read_npy(dir_.string()); }).find("is a directory, not a regular file"), std::string::npos);
}

// the loss and gradient of one env at x
std::pair<double, std::vector<double>> loss_and_grad(const Env& env, const std::vector<double>& x) {
  std::vector<double> g(x.size());
  const double loss = env.loss_and_grad(x, g);
  return {loss, g};
}

std::vector<double> seeded_point(int dim, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<double> x(static_cast<std::size_t>(dim));
  for (auto& v : x) v = 0.8 * (2.0 * rng.uniform() - 1.0);
  return x;
}

TEST_F(NpyTarget, HeadersAreReadByPythonsLiteralRulesAsNumpyReadsThem) {
  // numpy's verdict on each header, from np.load in the files' script
  std::map<std::string, std::string> numpy;
  {
    std::ifstream in(dir_ / "numpy_verdicts.txt");
    for (std::string name, verdict; in >> name >> verdict;) numpy[name] = verdict;
  }
  ASSERT_EQ(numpy.size(), 13u);
  struct Case {
    const char* name;
    const char* problem;  // "" when we read it
  };
  const Case cases[] = {
      {"h_plain.npy", ""},
      {"h_leading_zero.npy", "the integer '02' with a leading zero, which Python's literals (and so numpy) refuse"},
      {"h_zeros.npy", ""},  // 00 is Python's 0
      {"h_list.npy", "shape is not a tuple"},
      {"h_parenthesised_int.npy", "shape is not a tuple"},  // (2) is the integer 2
      {"h_nested_parens.npy", ""},
      {"h_spaced.npy", ""},
      {"h_long_v1.npy", ""},  // numpy reads versions 1.0 and 2.0 again with Python 2's L dropped
      {"h_long_v2.npy", ""},
      {"h_long_v3.npy", "Python 2's long suffix 'L', which numpy reads in format versions 1.0 and 2.0 only"},
      // numpy on Python 3.10 and later reads it, on earlier ones not: we keep to what both read
      {"h_leading_space.npy", "'{' expected first"},
      {"h_escape.npy", "dtype '<f8\\x1b[2J' is not read"},  // a control character shown as its escape
      {"target_leading_zero.npy", "the integer '064' with a leading zero"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string why = refusal([&] { read_npy(file(c.name)); });
    if (std::string(c.problem).empty()) {
      EXPECT_EQ(why, "");
    } else {
      EXPECT_NE(why.find(c.problem), std::string::npos) << why;
      EXPECT_EQ(why.rfind(file(c.name) + ": ", 0), 0u) << why;
      EXPECT_EQ(why.find_first_of("\n\x1b"), std::string::npos) << why;
    }
    // what numpy refuses, we refuse
    if (numpy.at(c.name) == "refuses") {
      EXPECT_NE(why, "");
    }
  }
  EXPECT_EQ(numpy.at("h_leading_zero.npy"), "refuses");
  EXPECT_EQ(numpy.at("target_leading_zero.npy"), "refuses");
  EXPECT_EQ(numpy.at("h_list.npy"), "refuses");
  EXPECT_EQ(numpy.at("h_parenthesised_int.npy"), "refuses");
  EXPECT_EQ(numpy.at("h_long_v3.npy"), "refuses");
  EXPECT_EQ(numpy.at("h_long_v1.npy"), "accepts");
  EXPECT_EQ(read_npy(file("h_long_v1.npy")).shape, std::vector<std::size_t>{2});
  EXPECT_EQ(read_npy(file("h_nested_parens.npy")).shape, std::vector<std::size_t>{2});
  EXPECT_EQ(read_npy(file("h_zeros.npy")).shape, std::vector<std::size_t>{0});
}

TEST_F(NpyTarget, ATargetMustBeAMassGrid) {
  const auto cfg = mpm::plb_config("pinch");
  const std::pair<const char*, const char*> bad[] = {
      {"target_negative.npy", "value -5 at [5, 6, 7] is negative: a target is a grid of masses"},
      {"target_all_negative.npy", "value -1 at [0, 0, 0] is negative"},
      {"target_below_tolerance.npy", "value -0.00010001 at [5, 6, 7] is negative"},
      {"target_zero.npy", "no positive mass (the largest value is 0)"},
      {"target_huge.npy", "value 1.7e+308 at [5, 6, 7] is above 1e+299, where the loss could overflow"},
  };
  for (const auto& [name, problem] : bad) {
    SCOPED_TRACE(name);
    const std::string why = refusal([&] { read_plb_target(file(name), cfg.mpm); });
    expect_names_file_and_problem(why, name, problem);
    EXPECT_EQ(why.find('\n'), std::string::npos) << why;
  }
  // PlasticineLab's own files hold negatives down to -2.3e-5: those load, and so does -1e-4 itself
  const auto tiny = read_plb_target(file("target_tiny_negative.npy"), cfg.mpm);
  EXPECT_EQ(tiny.grid.at(61, 61, 61), -2.3e-5);
  EXPECT_EQ(tiny.grid.at(63, 2, 4), -1e-4);
  EXPECT_EQ(-mpm::kTargetNegativeTolerance, -1e-4);
  // the density term sums |m - t| as it says, the negatives included: where no plasticine reaches,
  // a cell at -v adds what one at +v adds, so the loss and gradient are the same bits (the sum of
  // t there, as before, made them differ)
  const auto negative = make_env("plb-pinch-h5", {{"target", file("target_tiny_negative.npy")}});
  const auto positive = make_env("plb-pinch-h5", {{"target", file("target_tiny_positive.npy")}});
  const auto x = seeded_point(negative->dim(), 9);
  const auto [ln, gn] = loss_and_grad(*negative, x);
  const auto [lp, gp] = loss_and_grad(*positive, x);
  EXPECT_TRUE(std::isfinite(ln));
  EXPECT_EQ(ln, lp);
  EXPECT_EQ(gn, gp);
  // every cell at the upper bound: loss and gradient finite, the density term as large as the bound
  // allows (h5: 5 steps x 10 x 64^3 x 1e299 = 1.3e306; 50 steps would be 1.3e307 < 1.8e308)
  const auto at_bound = make_env("plb-pinch-h5", {{"target", file("target_at_bound.npy")}});
  const auto [lb, gb] = loss_and_grad(*at_bound, x);
  EXPECT_TRUE(std::isfinite(lb)) << lb;
  EXPECT_GT(lb, 1.3e306);
  EXPECT_LT(lb, 1.32e306);
  for (double g : gb) EXPECT_TRUE(std::isfinite(g)) << g;
}

TEST_F(NpyTarget, TargetLandsOnOurNodesAndIsKnownByItsValues) {
  const auto cfg = mpm::plb_config("pinch");
  ASSERT_EQ(cfg.mpm.pad, 1);
  const auto raw = read_npy(file("target_a.npy"));
  const auto t = read_plb_target(file("target_a.npy"), cfg.mpm);
  ASSERT_EQ(t.grid.n, (std::array<int, 3>{65, 65, 65}));
  double pad_sum = 0.0;
  std::size_t n = 0;
  for (int i = 0; i < 65; ++i)
    for (int j = 0; j < 65; ++j)
      for (int k = 0; k < 65; ++k) {
        if (i == 0 || j == 0 || k == 0) {
          pad_sum += std::abs(t.grid.at(i, j, k));
          continue;
        }
        // entry [i-1, j-1, k-1], at ((i-1), (j-1), (k-1)) dx, is our node (i, j, k), at (I - pad) dx
        ASSERT_EQ(t.grid.at(i, j, k), raw.values[n++]) << i << " " << j << " " << k;
      }
  EXPECT_EQ(pad_sum, 0.0);
  EXPECT_EQ(t.grid.at(21, 1, 21), raw.values[(20 * 64 + 0) * 64 + 20]);
  EXPECT_GT(t.grid.at(21, 1, 21), 0.0);
  // the round trip back to PlasticineLab's nodes
  EXPECT_EQ(mpm::plb_node_values(t.grid, cfg.mpm), raw.values);

  // identity: the values, not the path or the dtype
  const auto b = read_plb_target(file("target_b.npy"), cfg.mpm);
  const auto f4 = read_plb_target(file("target_a_f4.npy"), cfg.mpm);
  const auto f4_as_f8 = read_plb_target(file("target_a_f4_as_f8.npy"), cfg.mpm);
  EXPECT_EQ(t.hash.size(), 16u);
  EXPECT_NE(t.hash, b.hash);
  EXPECT_NE(t.hash, f4.hash);
  EXPECT_EQ(f4.hash, f4_as_f8.hash);
  EXPECT_EQ(f4.grid.values, f4_as_f8.grid.values);
  EXPECT_EQ(f4.dtype, "<f4");
  fs::copy_file(file("target_a.npy"), file("target_a_copy.npy"), fs::copy_options::overwrite_existing);
  EXPECT_EQ(read_plb_target(file("target_a_copy.npy"), cfg.mpm).hash, t.hash);

  const std::pair<const char*, const char*> bad[] = {
      {"target_2d.npy", "shape (64, 64) is not a target grid's (64, 64, 64)"},
      {"target_65.npy", "shape (65, 64, 64) is not a target grid's (64, 64, 64)"},
      {"target_nan.npy", "value nan at [1, 2, 3] is not finite"},
      {"target_fortran.npy", "Fortran order"},
      {"target_truncated.npy", "truncated data"},
  };
  for (const auto& [name, problem] : bad) {
    SCOPED_TRACE(name);
    const std::string why = refusal([&] { read_plb_target(file(name), cfg.mpm); });
    expect_names_file_and_problem(why, name, problem);
  }
}

// the hash the regression baseline stores for this env's runs
std::string baseline_env_hash(const std::string& env) {
  std::ifstream in(std::string(DSB_SOURCE_DIR) + "/data/baselines/small-grid.csv");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(env + ",", 0) == 0) {
      std::vector<std::string> cells;
      std::stringstream s(line);
      for (std::string c; std::getline(s, c, ',');) cells.push_back(c);
      return cells.at(4);
    }
  return "";
}

TEST_F(NpyTarget, EnvConfigHashIsTheTargetsAndUnchangedWithout) {
  const std::string builtin = config_hash(make_env("plb-pinch-h5")->config());
  EXPECT_EQ(builtin, baseline_env_hash("plb-pinch-h5"));
  EXPECT_EQ(config_hash(make_env("plb-writer-h5")->config()), baseline_env_hash("plb-writer-h5"));
  const auto a = make_env("plb-pinch-h5", {{"target", file("target_a.npy")}});
  const auto b = make_env("plb-pinch-h5", {{"target", file("target_b.npy")}});
  fs::copy_file(file("target_a.npy"), file("target_a_copy.npy"), fs::copy_options::overwrite_existing);
  const auto a2 = make_env("plb-pinch-h5", {{"target", file("target_a_copy.npy")}});
  EXPECT_NE(config_hash(a->config()), builtin);
  EXPECT_NE(config_hash(a->config()), config_hash(b->config()));
  EXPECT_EQ(config_hash(a->config()), config_hash(a2->config()));  // another path, the same values
  const auto target = a->config().at("target");
  EXPECT_EQ(target.at("values_fnv1a64"), read_plb_target(file("target_a.npy"), mpm::plb_config("pinch").mpm).hash);
  EXPECT_EQ(a->config().dump().find(dir_.string()), std::string::npos);  // no path in the config
  EXPECT_FALSE(target.contains("reference_motion"));
  // everything but the target is the built-in env's
  auto without = a->config();
  auto builtin_config = make_env("plb-pinch-h5")->config();
  without.erase("target");
  builtin_config.erase("target");
  EXPECT_EQ(without, builtin_config);
  EXPECT_EQ(a->dim(), 15);
}

TEST_F(NpyTarget, OptionsTheEnvDoesNotTakeAreRefusedByKey) {
  const std::string none = refusal([&] { make_env("sphere-10", {{"target", file("target_a.npy")}}); });
  EXPECT_NE(none.find("env 'sphere-10' takes no options, got 'target'"), std::string::npos) << none;
  const std::string unknown = refusal([&] { make_env("plb-pinch-h5", {{"tagret", file("target_a.npy")}}); });
  EXPECT_NE(unknown.find("env 'plb-pinch-h5' has no option 'tagret' (its options: target)"), std::string::npos)
      << unknown;
  const std::string bad = refusal([&] { make_env("plb-pinch-h5", {{"target", file("target_2d.npy")}}); });
  EXPECT_EQ(bad.rfind("plb-pinch-h5.target: " + file("target_2d.npy") + ": shape (64, 64)", 0), 0u) << bad;
  EXPECT_NE(refusal([&] {
              shared_env("plb-pinch-h5", {{"target", file("missing.npy")}});
            }).find("cannot open"),
            std::string::npos);
  const auto& family = env_family_of("plb-rope-h10");
  ASSERT_EQ(family.options.size(), 1u);
  EXPECT_EQ(family.options[0].key, "target");
  EXPECT_TRUE(family.options[0].path);
  EXPECT_TRUE(env_family_of("sphere-10").options.empty());
}

TEST_F(NpyTarget, LoadedCopyOfOurTargetGivesTheBuiltInLossBitForBit) {
  // Table's generated target has no mass on the pad nodes PlasticineLab's grid lacks, so its
  // .npy copy is the whole target: the same loss and gradient, bit for bit
  const auto stored = mpm::read_grid_gz(mpm::plb_target_path("table"));
  double pad_mass = 0.0;
  for (int i = 0; i < 65; ++i)
    for (int j = 0; j < 65; ++j)
      for (int k = 0; k < 65; ++k)
        if (i == 0 || j == 0 || k == 0) pad_mass += std::abs(stored.at(i, j, k));
  ASSERT_EQ(pad_mass, 0.0);
  const auto builtin = make_env("plb-table-h5");
  const auto loaded = make_env("plb-table-h5", {{"target", file("ours_table.npy")}});
  const auto& model = static_cast<const mpm::PlbEnv&>(*loaded).model();
  EXPECT_EQ(model.target.values, stored.values);
  const auto x = seeded_point(loaded->dim(), 5);
  const auto [l0, g0] = loss_and_grad(*builtin, x);
  const auto [l1, g1] = loss_and_grad(*loaded, x);
  EXPECT_TRUE(std::isfinite(l0));
  EXPECT_GT(l0, 1.0);
  EXPECT_EQ(l1, l0);
  EXPECT_EQ(g1, g0);
  EXPECT_EQ(loaded->loss(x), l0);
  EXPECT_NE(config_hash(loaded->config()), config_hash(builtin->config()));  // a file is never the built-in

  // Pinch's generated target holds 7e-5 of its 0.37 on the pad row below y = 0; the copy is the
  // rest, node for node, and a different target, so a different loss
  const auto pinch = make_env("plb-pinch-h5", {{"target", file("ours_pinch.npy")}});
  auto expected = mpm::read_grid_gz(mpm::plb_target_path("pinch"));
  double dropped = 0.0;
  for (int i = 0; i < 65; ++i)
    for (int j = 0; j < 65; ++j)
      for (int k = 0; k < 65; ++k)
        if (i == 0 || j == 0 || k == 0) {
          dropped += expected.at(i, j, k);
          expected.at(i, j, k) = 0.0;
        }
  EXPECT_GT(dropped, 1e-5);
  EXPECT_LT(dropped, 1e-4);
  EXPECT_EQ(static_cast<const mpm::PlbEnv&>(*pinch).model().target.values, expected.values);
  const auto xp = seeded_point(pinch->dim(), 5);
  EXPECT_NE(pinch->loss(xp), make_env("plb-pinch-h5")->loss(xp));
}

// `harness eval`'s JSON
nlohmann::json eval_json(const testing::HarnessResult& r) { return nlohmann::json::parse(r.out); }

std::string zeros(int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += i ? ",0" : "0";
  return s;
}

TEST_F(NpyTarget, HarnessEvalTakesTheTargetAndRefusesBadFiles) {
  const fs::path run = dir_ / "eval";
  fs::create_directories(run);
  auto harness = [&](const std::string& args) { return testing::run_harness(run, args); };
  const std::string x = " --x " + zeros(15);
  const auto with = harness("eval --env plb-table-h5 --set plb-table-h5.target=" + file("ours_table.npy") + x);
  ASSERT_EQ(with.code, 0) << with.err;
  const auto without = harness("eval --env plb-table-h5" + x);
  ASSERT_EQ(without.code, 0) << without.err;
  EXPECT_EQ(eval_json(with)["loss"].get<double>(), eval_json(without)["loss"].get<double>());
  const auto other = harness("eval --env plb-table-h5 --set plb-table-h5.target=" + file("target_a.npy") + x);
  ASSERT_EQ(other.code, 0) << other.err;
  const double other_loss = eval_json(other)["loss"].get<double>();
  EXPECT_NE(other_loss, eval_json(without)["loss"].get<double>());
  EXPECT_EQ(other_loss, make_env("plb-table-h5", {{"target", file("target_a.npy")}})->loss(std::vector<double>(15)));

  const std::pair<std::string, std::string> bad[] = {
      {"missing.npy", "cannot open"},
      {"not_npy.npy", "not a .npy file"},
      {"version4.npy", "unsupported .npy version 4.0"},
      {"int32.npy", "dtype '<i4'"},
      {"target_2d.npy", "shape (64, 64)"},
      {"target_fortran.npy", "Fortran order"},
      {"target_truncated.npy", "truncated data"},
      {"target_negative.npy", "value -5 at [5, 6, 7] is negative"},
      {"target_all_negative.npy", "value -1 at [0, 0, 0] is negative"},
      {"target_zero.npy", "no positive mass"},
      {"target_huge.npy", "value 1.7e+308 at [5, 6, 7] is above 1e+299"},
      {"target_leading_zero.npy", "the integer '064' with a leading zero"},
  };
  for (const auto& [name, problem] : bad) {
    SCOPED_TRACE(name);
    const auto r = harness("eval --env plb-table-h5 --set plb-table-h5.target=" + file(name) + x);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err.rfind("harness: error: plb-table-h5.target: " + file(name) + ": ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(problem), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty());
  }
  auto refused = [&](const std::string& args, const std::string& words) {
    const auto r = harness(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_NE(r.err.find(words), std::string::npos) << args << "\n" << r.err;
  };
  refused("eval --env plb-table-h5 --set plb-table-h5.tagret=F" + x, "has no option 'tagret'");
  refused("eval --env sphere-3 --set sphere-3.target=F --x 0,0,0", "env 'sphere-3' takes no options, got 'target'");
  refused("eval --env plb-table-h5 --set plb-pinch-h5.target=F" + x, "--set names 'plb-pinch-h5'");
  refused("eval --env plb-table-h5 --set target=F" + x, "--set wants");
}

TEST_F(NpyTarget, GridPlanSlurmAndListPassTheTargetOn) {
  const fs::path run = dir_ / "grid";
  fs::create_directories(run);
  auto harness = [&](const std::string& args) { return testing::run_harness(run, args, "cd " + run.string() + " &&"); };
  const std::string db = (run / "r.sqlite").string();
  const std::string grid = "--env plb-pinch-h5 --optimizer random --seeds 1 --budget 1 --quiet --db " + db;
  fs::copy_file(file("target_a.npy"), run / "mine.npy", fs::copy_options::overwrite_existing);

  const auto first = harness(grid + " --set plb-pinch-h5.target=mine.npy");
  ASSERT_EQ(first.code, 0) << first.err;
  const auto builtin = harness(grid);
  ASSERT_EQ(builtin.code, 0) << builtin.err;
  EXPECT_NE(builtin.err.find("0 already done, 1 done now"), std::string::npos) << builtin.err;
  // the same values from another path: the same run, already done
  const auto again = harness(grid + " --set plb-pinch-h5.target=" + file("target_a_copy.npy"));
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.err.find("1 already done, 0 done now"), std::string::npos) << again.err;
  const auto hashes = testing::quiet_scalar(db,
                                            "SELECT group_concat(env_config_hash, ' ') FROM "
                                            "(SELECT env_config_hash FROM runs ORDER BY run_id)");
  const std::string with_target = config_hash(make_env("plb-pinch-h5", {{"target", file("target_a.npy")}})->config());
  EXPECT_EQ(hashes, with_target + " " + baseline_env_hash("plb-pinch-h5"));
  // the two runs' losses differ: each has its own target
  const auto losses = testing::rows(db, "SELECT best_loss FROM runs ORDER BY run_id");
  ASSERT_EQ(losses.size(), 2u);
  EXPECT_NE(losses[0], losses[1]);

  // a bad file stops the grid before the database is opened
  const std::string db2 = (run / "bad.sqlite").string();
  const auto bad = harness("--env plb-pinch-h5 --optimizer random --budget 1 --quiet --db " + db2 +
                           " --set plb-pinch-h5.target=" + file("target_65.npy"));
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("plb-pinch-h5.target: " + file("target_65.npy") + ": shape (65, 64, 64)"), std::string::npos)
      << bad.err;
  EXPECT_FALSE(fs::exists(db2));
  const auto neither = harness(grid + " --set plb-writer-h5.target=mine.npy");
  EXPECT_EQ(neither.code, 2);
  EXPECT_NE(neither.err.find("--set names 'plb-writer-h5', which is neither an env nor an optimizer of the grid"),
            std::string::npos)
      << neither.err;

  // plan reads the target (its runs are pending until run) and refuses a bad one
  const auto plan = harness("plan " + grid + " --set plb-pinch-h5.target=" + file("target_b.npy"));
  ASSERT_EQ(plan.code, 0) << plan.err;
  EXPECT_NE(plan.out.find("--set plb-pinch-h5.target=" + file("target_b.npy")), std::string::npos) << plan.out;
  EXPECT_EQ(harness("plan " + grid + " --set plb-pinch-h5.target=" + file("version4.npy")).code, 2);

  // slurm's tasks get the target as an absolute path (they run elsewhere), a knob as it is
  const auto slurm = harness(
      "slurm --env plb-pinch-h5 --optimizer rand-descents --seeds 1 --budget 1 --shards 1 "
      "--dir s --set plb-pinch-h5.target=mine.npy --set rand-descents.max_steps=7");
  ASSERT_EQ(slurm.code, 0) << slurm.err;
  const std::string sbatch = testing::read_file(run / "s" / "array.sbatch");
  const std::string absolute = "--set plb-pinch-h5.target=" + (run / "mine.npy").string();
  EXPECT_NE(sbatch.find(absolute + " --set rand-descents.max_steps=7 "), std::string::npos) << sbatch;

  const auto list = harness("list");
  ASSERT_EQ(list.code, 0);
  const auto at = list.out.find("env options (--set ENV.KEY=VALUE");
  ASSERT_NE(at, std::string::npos) << list.out;
  EXPECT_NE(list.out.find("plb-NAME               target   a PlasticineLab-format .npy target grid", at),
            std::string::npos)
      << list.out;
}

TEST_F(NpyTarget, CompareScriptPutsOursBesidePlasticineLabs) {
  const fs::path assets = dir_ / "checkout" / "plb" / "envs" / "assets";
  fs::create_directories(assets);
  fs::copy_file(file("ours_pinch.npy"), assets / "Pinch3D-v1.npy", fs::copy_options::overwrite_existing);
  fs::copy_file(file("target_a.npy"), assets / "Table3D-v1.npy", fs::copy_options::overwrite_existing);
  fs::copy_file(file("target_2d.npy"), assets / "Rope3D-v1.npy", fs::copy_options::overwrite_existing);
  const fs::path build = fs::path(DSB_HARNESS_EXE).parent_path().parent_path();
  const std::string script = std::string(DSB_SOURCE_DIR) + "/scripts/plb-targets.sh compare ";
  const auto out = dir_ / "compare.out";
  const auto run = [&](const fs::path& where) {
    const std::string cmd = script + where.string() + " " + build.string() + " > " + out.string() + " 2>&1";
    const int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  EXPECT_EQ(run(dir_ / "checkout"), 1);  // Rope3D-v1.npy cannot be read as a target
  const std::string text = testing::read_file(out);
  // our own pinch target beside itself: its nodes above 1e-4 all overlap (the pad row holds less)
  EXPECT_NE(text.find("Pinch3D-v1.npy       [0.391, 0.625]  [0.000, 0.219]  [0.391, 0.594]"), std::string::npos)
      << text;
  EXPECT_NE(text.find("overlap (IoU of nodes > 0.0001) 1.000"), std::string::npos) << text;
  EXPECT_NE(text.find("Table3D-v1.npy       [0.312, 0.672]  [0.000, 0.141]  [0.312, 0.672]"), std::string::npos)
      << text;
  EXPECT_NE(text.find("Rope3D-v1.npy: shape (64, 64)"), std::string::npos) << text;
  EXPECT_NE(text.find("Writer3D-v1.npy: not in"), std::string::npos) << text;
  EXPECT_EQ(run(assets), 1);  // the assets folder itself works too
  fs::create_directories(dir_ / "empty");
  EXPECT_EQ(run(dir_ / "empty"), 2);  // no PlasticineLab file at all
}

}  // namespace
}  // namespace dsb
