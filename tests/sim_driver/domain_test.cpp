#include "sim_driver/registry/domain.hpp"
#include "sim_driver/registry/simulation_options.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "learner/input_error.hpp"

namespace hbirl {
namespace {

// A file in the temporary folder, removed at the end of the test.
struct TempFile {
  std::string path;
  TempFile(const std::string& name, const std::string& text)
      : path((std::filesystem::temp_directory_path() / ("hbirl_" + std::to_string(::getpid()) + "_" + name)).string()) {
    std::ofstream(path) << text;
  }
  ~TempFile() { std::filesystem::remove(path); }
};

// Three states in a row, the last terminal; "right" moves on with probability 0.9.
// The subject's symbol is its state (0.7) or another; the element always shows symbol 2.
std::string tiny_domain(const std::string& name, const std::string& eta, double occlusion) {
  return R"({"name": ")" + name + R"(",
    "mdp": {"num_states": 3, "num_actions": 2, "num_features": 1,
            "transitions": [[0, 0, 0, 1.0], [0, 1, 1, 0.9], [0, 1, 0, 0.1], [1, 0, 0, 1.0], [1, 1, 2, 0.9], [1, 1, 1, 0.1]],
            "terminal": [2], "start": [[0, 1.0]], "features": [[1, 1, 0, 1.0]]},
    "observation_model": {"num_symbols": 3, "num_confounders": 1},
    "true_weights": [30.0],
    "sensor": {"subject_observation": [[0, 0, 0, 0.7], [0, 0, 1, 0.15], [0, 0, 2, 0.15],
                                       [0, 1, 0, 0.7], [0, 1, 1, 0.15], [0, 1, 2, 0.15],
                                       [1, 0, 1, 0.7], [1, 0, 0, 0.15], [1, 0, 2, 0.15],
                                       [1, 1, 1, 0.7], [1, 1, 0, 0.15], [1, 1, 2, 0.15]],
               "confounder_observation": [[0, 2, 1.0]],
               "observations_per_step": 4, "eta": ")" +
         eta + R"(", "occlusion": )" + std::to_string(occlusion) + R"(,
               "trajectories": 400, "length": 6, "controlled_trajectories": 50}})";
}

TEST(Domains, RegistryHasTheBuiltInOnesByName) {
  EXPECT_EQ(builtin_domain("onion")->name(), "onion");
  EXPECT_TRUE(builtin_domain("onion")->has_camera());
  EXPECT_EQ(builtin_domain("gridworld")->mdp().num_states, 25);
  EXPECT_FALSE(builtin_domain("gridworld")->has_camera());
  EXPECT_EQ(builtin_domain("gridworld:10")->mdp().num_states, 100);
  EXPECT_EQ(builtin_domain("gridworld:10")->name(), "gridworld:10");
  EXPECT_EQ(builtin_domain("chess"), nullptr);
  EXPECT_EQ(builtin_domain("gridworld:"), nullptr);
  EXPECT_EQ(builtin_domain("gridworld:1x"), nullptr);
  EXPECT_THROW(builtin_domain("gridworld:1"), InputError);
  EXPECT_THROW(builtin_domain("gridworld:9999"), InputError);
  DomainOptions seven;
  seven.gridworld_size = 7;
  EXPECT_EQ(open_domain("gridworld", seven)->mdp().num_states, 49);
  EXPECT_EQ(open_domain("gridworld", seven)->name(), "gridworld:7");
  // A name off the bus never opens a file.
  EXPECT_EQ(builtin_domain(std::string(HBIRL_SOURCE_DIR) + "/examples/warehouse.json"), nullptr);
}

TEST(Domains, FilesOpenByPathAndSayWhatIsWrong) {
  const auto warehouse = open_domain(std::string(HBIRL_SOURCE_DIR) + "/examples/warehouse.json");
  EXPECT_EQ(warehouse->name(), "warehouse");
  EXPECT_EQ(warehouse->num_symbols(), 7);
  const DomainNames n = warehouse->names(3);
  EXPECT_EQ(n.sources, (std::vector<std::string>{"picker (expert)", "forklift", "co-worker"}));
  EXPECT_EQ(n.symbols[4], "shelf row");
  EXPECT_EQ(n.features[2], "enter_spill");
  try {
    open_domain("/nonexistent/task.json");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "/nonexistent/task.json");
  }
  const TempFile onion("onion.json", tiny_domain("onion", "true", 0.0));
  try {
    open_domain(onion.path);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("built-in domain's name"), std::string::npos) << e.what();
  }
  // No sensor: a domain to learn on, nothing to simulate.
  const TempFile corridor_copy("corridor.json", R"({"mdp": {"num_states": 1, "num_actions": 1, "num_features": 0,
                                                   "transitions": [[0, 0, 0, 1.0]]}})");
  EXPECT_THROW(open_domain(corridor_copy.path)->simulate({}), InputError);
}

// The sensor as the domain file says: the expert from mdp.start until a terminal state or
// `length` steps; each step occluded with probability `occlusion`, else
// observations_per_step observations, each from the subject or the element with equal
// probability; eta "true" puts all of it on the true source; the controlled run is the
// subject's alone. Checked by counting over many trajectories.
TEST(Domains, FileSensorSimulatesWhatItsFileSays) {
  const TempFile file("tiny.json", tiny_domain("tiny", "true", 0.25));
  const auto domain = open_domain(file.path);
  SimulationOptions options;
  options.seed = 5;
  const auto run = domain->simulate(options);
  ASSERT_FALSE(run->camera());
  ASSERT_EQ(run->episodes.size(), 450u);
  EXPECT_EQ(run->num_sources, 2);
  EXPECT_EQ(run->num_symbols, 3);
  int occluded = 0, steps = 0, ended = 0;
  std::array<double, 3> subject_at_0{}, subject_at_1{};
  double from_element = 0, from_subject = 0;
  for (int id = 0; id < static_cast<int>(run->episodes.size()); ++id) {
    const auto& e = run->episodes[static_cast<size_t>(id)];
    const ObservedTrajectory& o = run->observed(id);
    EXPECT_EQ(e.controlled, id < 50);
    ASSERT_EQ(o.length(), static_cast<int>(e.steps.size()));
    EXPECT_LE(o.length(), 6);
    EXPECT_EQ(o.ends_in_terminal, e.ends_in_terminal);
    if (e.ends_in_terminal) ++ended;
    if (!e.ends_in_terminal) {
      EXPECT_EQ(o.length(), 6);
    }
    EXPECT_EQ(e.steps.front().state, 0);
    for (int t = 0; t < o.length(); ++t) {
      const int n = o.observations_at(t);
      EXPECT_TRUE(n == 0 || n == 4) << n;
      if (e.controlled) continue;
      ++steps;
      occluded += n == 0;
      for (int k = o.step_begin[static_cast<size_t>(t)]; k < o.step_begin[static_cast<size_t>(t) + 1]; ++k) {
        const int w = o.symbols[static_cast<size_t>(k)];
        EXPECT_DOUBLE_EQ(o.eta.row(k).maxCoeff(), 1.0);  // "true": one-hot
        if (o.eta(k, 1) == 1.0) {
          ++from_element;
          EXPECT_EQ(w, 2);
        } else {
          ++from_subject;
          (e.steps[static_cast<size_t>(t)].state == 0 ? subject_at_0 : subject_at_1)[static_cast<size_t>(w)] += 1;
        }
      }
    }
    if (e.controlled && o.num_observations() > 0) {
      EXPECT_EQ(o.eta.col(0).minCoeff(), 1.0);
    }
  }
  EXPECT_GT(ended, 300);  // worth more than looping forever (the soft expert's entropy): most walk out
  // Binomial bounds at about 5 standard deviations.
  const double p_occluded = static_cast<double>(occluded) / steps;
  EXPECT_NEAR(p_occluded, 0.25, 5 * std::sqrt(0.25 * 0.75 / steps));
  const double total = from_element + from_subject;
  EXPECT_NEAR(from_subject / total, 0.5, 5 * std::sqrt(0.25 / total));
  const double n0 = subject_at_0[0] + subject_at_0[1] + subject_at_0[2];
  const double n1 = subject_at_1[0] + subject_at_1[1] + subject_at_1[2];
  EXPECT_NEAR(subject_at_0[0] / n0, 0.7, 5 * std::sqrt(0.21 / n0));
  EXPECT_NEAR(subject_at_1[1] / n1, 0.7, 5 * std::sqrt(0.21 / n1));
  // The same seed, the same run; another seed, another.
  const auto again = domain->simulate(options);
  EXPECT_EQ(again->observed(60).symbols, run->observed(60).symbols);
  options.seed = 6;
  EXPECT_NE(domain->simulate(options)->observed(60).symbols, run->observed(60).symbols);
}

// A domain file's end sensor (sensor.end_observation, end_reports): each demonstration that
// entered the terminal state carries end_reports reports drawn from its row of O_end, the
// cut-off ones and the controlled run none; the rest of the run is as without it.
TEST(Domains, FileSensorReportsEndingsAsItsFileSays) {
  std::string text = tiny_domain("tiny", "true", 0.25);
  const std::string model = R"("num_confounders": 1})";
  text.replace(text.find(model), model.size(), R"("num_confounders": 1, "end_sensor": {"num_symbols": 2}})");
  text.replace(text.find(R"("observations_per_step")"), 0,
               R"("end_observation": [[2, 0, 0.8], [2, 1, 0.2]], "end_reports": 3, )");
  const TempFile file("tiny.json", text);
  const auto domain = open_domain(file.path);
  SimulationOptions options;
  options.seed = 5;
  const auto run = domain->simulate(options);
  EXPECT_EQ(run->num_end_symbols, 2);
  const TempFile plain_file("tiny.json", tiny_domain("tiny", "true", 0.25));
  const auto plain = open_domain(plain_file.path)->simulate(options);
  double zeros = 0, reports = 0;
  for (int id = 0; id < static_cast<int>(run->episodes.size()); ++id) {
    const auto& e = run->episodes[static_cast<size_t>(id)];
    const ObservedTrajectory& o = run->observed(id);
    EXPECT_EQ(o.symbols, plain->observed(id).symbols);  // the same run besides
    EXPECT_EQ(o.end_symbols.size(), e.ends_in_terminal && !e.controlled ? 3u : 0u) << id;
    for (int w : o.end_symbols) zeros += w == 0;
    reports += static_cast<double>(o.end_symbols.size());
  }
  ASSERT_GT(reports, 600);
  EXPECT_NEAR(zeros / reports, 0.8, 5 * std::sqrt(0.16 / reports));
  // Without an end sensor in the observation model there is nothing to report with.
  std::string orphan = tiny_domain("tiny", "true", 0.25);
  orphan.replace(orphan.find(R"("observations_per_step")"), 0, R"("end_reports": 2, )");
  const TempFile orphan_file("tiny.json", orphan);
  try {
    open_domain(orphan_file.path);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), orphan_file.path + ": sensor.end_reports");
  }
}

TEST(Domains, PlausibleEtaFavoursTheTrueSourceFourTimesInFive) {
  const TempFile file("plausible.json", tiny_domain("tiny", "plausible", 0.0));
  const auto run = open_domain(file.path)->simulate({});
  double rows = 0;
  for (int id = 50; id < static_cast<int>(run->episodes.size()); ++id) {
    const ObservedTrajectory& o = run->observed(id);
    for (Eigen::Index k = 0; k < o.eta.rows(); ++k) {
      EXPECT_DOUBLE_EQ(o.eta.row(k).maxCoeff(), 0.6);
      EXPECT_DOUBLE_EQ(o.eta.row(k).sum(), 1.0);
      ++rows;
    }
  }
  EXPECT_GT(rows, 1000);
}

}  // namespace
}  // namespace hbirl
