// talus's DTW against the Python package the paper used (similaritymeasures.dtw), on random
// trajectories of unequal length. The package lives in a venv at <build>/venv, created here on
// first use; without network access to PyPI this test fails (it never skips).
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "sim2real/metrics.hpp"
#include "tests/sim2real/synthetic_runs.hpp"

namespace talus::sim2real {
namespace {

namespace fs = std::filesystem;

// agreement required between the two implementations [m]
constexpr double kAgreement = 1e-9;

int run(const std::string& command) { return std::system(command.c_str()); }

std::string quote(const fs::path& p) { return "'" + p.string() + "'"; }

// <build>/venv/bin/python with similaritymeasures importable, or an explanation of why not
fs::path reference_python(std::string& why) {
  const fs::path venv = fs::path(TALUS_BINARY_DIR) / "venv";
  const fs::path python = venv / "bin" / "python";
  const std::string probe = quote(python) + " -c 'import similaritymeasures' >/dev/null 2>&1";
  if (fs::exists(python) && run(probe) == 0) return python;
  // idempotent set-up: create the venv if needed, then install the package into it
  if (!fs::exists(python) && run("python3 -m venv " + quote(venv)) != 0) {
    why = "could not create " + venv.string() + " with 'python3 -m venv' (install python3-venv)";
    return {};
  }
  if (run(quote(python) + " -m pip install -q similaritymeasures") != 0 || run(probe) != 0) {
    why = "could not install similaritymeasures into " + venv.string() +
          " (is PyPI reachable? run: " + python.string() +
          " -m pip install similaritymeasures)";
    return {};
  }
  return python;
}

void write_points(const fs::path& file, const Trajectory& x) {
  std::ofstream out(file);
  out.precision(17);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (Eigen::Index j = 0; j < x.cols(); ++j) out << (j ? " " : "") << x(i, j);
    out << "\n";
  }
}

TEST(DtwTest, MatchesSimilaritymeasuresOnRandomTrajectories) {
  std::string why;
  const fs::path python = reference_python(why);
  ASSERT_FALSE(python.empty()) << "similaritymeasures reference unavailable: " << why;

  // random walks (like bucket-tip paths) and white noise, unequal lengths, 1-D to 3-D
  struct Case {
    int n, m, dims;
    bool walk;
  };
  const std::vector<Case> cases = {{1, 5, 2, false},    {5, 1, 2, false},   {2, 3, 2, false},
                                   {17, 29, 2, true},   {100, 73, 2, true}, {250, 400, 2, true},
                                   {60, 45, 3, false},  {30, 20, 1, true},  {301, 287, 2, true}};
  std::mt19937_64 rng(20240531);  // fixed seed: the same trajectories every run
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  auto make = [&](int rows, int dims, bool walk) {
    Trajectory x(rows, dims);
    for (int i = 0; i < rows; ++i) {
      for (int j = 0; j < dims; ++j) {
        const double step = uniform(rng);
        x(i, j) = walk && i > 0 ? x(i - 1, j) + 0.05 * step : step;
      }
    }
    return x;
  };
  const fs::path dir = test::fresh_temp_dir("dtw");
  std::vector<double> ours;
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const Trajectory a = make(cases[k].n, cases[k].dims, cases[k].walk);
    const Trajectory b = make(cases[k].m, cases[k].dims, cases[k].walk);
    write_points(dir / ("a_" + std::to_string(k) + ".txt"), a);
    write_points(dir / ("b_" + std::to_string(k) + ".txt"), b);
    ours.push_back(dtw_distance(a, b));
  }

  // the reference distances, one line per case
  const std::string script = std::string(TALUS_SOURCE_DIR) + "/tests/sim2real/dtw_reference.py";
  const std::string command = quote(python) + " " + quote(script) + " " + quote(dir) + " " +
                              std::to_string(cases.size());
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr) << command;
  std::string text;
  char buffer[256];
  while (fgets(buffer, sizeof buffer, pipe)) text += buffer;
  ASSERT_EQ(pclose(pipe), 0) << "reference script failed: " << command;

  std::istringstream lines(text);
  std::vector<double> theirs;
  for (double v; lines >> v;) theirs.push_back(v);
  ASSERT_EQ(theirs.size(), cases.size()) << text;
  for (std::size_t k = 0; k < cases.size(); ++k) {
    EXPECT_GT(theirs[k], 0.0) << "case " << k;
    EXPECT_NEAR(ours[k], theirs[k], kAgreement)
        << "case " << k << ": " << cases[k].n << " x " << cases[k].m << " points, "
        << cases[k].dims << "-D";
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace talus::sim2real
