#include "problem/domain_file.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <nlohmann/json.hpp>

#include "learner/input_error.hpp"

namespace hbirl {
namespace {

using nlohmann::json;

// A two-state domain with one confounding element and a sensor (docs/your-task.md "Your own task").
json tiny_domain() {
  return json::parse(R"({
    "name": "tiny",
    "mdp": {
      "num_states": 3, "num_actions": 2, "num_features": 1,
      "transitions": [[0, 0, 0, 1.0], [0, 1, 1, 1.0], [1, 0, 0, 1.0], [1, 1, 2, 1.0]],
      "terminal": [2],
      "start": [[0, 1.0]],
      "features": [[1, 1, 0, 1.0]]
    },
    "observation_model": {"num_symbols": 3, "num_confounders": 1},
    "symbol_names": ["left", "right", "door"],
    "source_names": ["robot", "cat"],
    "true_weights": [2.0],
    "sensor": {
      "subject_observation": [[0, 0, 0, 0.8], [0, 0, 1, 0.2], [1, 1, 2, 0.5], [1, 1, 1, 0.5]],
      "confounder_observation": [[0, 2, 1.0]],
      "observations_per_step": 3, "eta": "true", "occlusion": 0.25,
      "trajectories": 7, "length": 4, "controlled_trajectories": 2
    }
  })");
}

DomainSpec parse(const json& doc, std::vector<std::string>* warnings = nullptr) {
  return parse_domain(doc.dump(), "stem", warnings);
}

TEST(DomainFile, ReadsEverySection) {
  std::vector<std::string> warnings;
  const DomainSpec d = parse(tiny_domain(), &warnings);
  EXPECT_TRUE(warnings.empty());
  EXPECT_EQ(d.name, "tiny");
  EXPECT_EQ(d.mdp.num_states, 3);
  EXPECT_EQ(d.num_symbols(), 3);
  EXPECT_EQ(d.num_sources(), 2);
  EXPECT_EQ(d.symbol_names[2], "door");
  EXPECT_EQ(d.source_names[1], "cat");
  ASSERT_TRUE(d.sensor.has_value());
  const SensorSpec& s = *d.sensor;
  // Listed rows as given, unlisted rows uniform.
  EXPECT_DOUBLE_EQ(s.subject_o(d.mdp.pair(0, 0), 0), 0.8);
  EXPECT_DOUBLE_EQ(s.subject_o(d.mdp.pair(0, 0), 2), 0.0);
  EXPECT_DOUBLE_EQ(s.subject_o(d.mdp.pair(1, 1), 2), 0.5);
  EXPECT_DOUBLE_EQ(s.subject_o(d.mdp.pair(0, 1), 1), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(s.confounder_o(0, 2), 1.0);
  EXPECT_EQ(s.observations_per_step, 3);
  EXPECT_EQ(s.eta, "true");
  EXPECT_DOUBLE_EQ(s.occlusion, 0.25);
  EXPECT_EQ(s.trajectories, 7);
  EXPECT_EQ(s.length, 4);
  EXPECT_EQ(s.controlled_trajectories, 2);
}

TEST(DomainFile, NameDefaultsToTheStemAndAProblemFileIsADomain) {
  json doc = tiny_domain();
  doc.erase("name");
  doc["demonstration"] = json::array();  // a problem file's data: not read here, no warning
  std::vector<std::string> warnings;
  EXPECT_EQ(parse(doc, &warnings).name, "stem");
  EXPECT_TRUE(warnings.empty());
  doc["sensr"] = 1;
  parse(doc, &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("sensr"), std::string::npos);
}

// Every class of bad domain file: one line, naming the field.
TEST(DomainFile, BadFilesNameTheField) {
  const std::vector<std::pair<std::function<void(json&)>, std::string>> cases = {
      {[](json& d) { d.erase("mdp"); }, "mdp: missing"},
      {[](json& d) { d["name"] = "two words"; }, "name: may hold"},
      {[](json& d) { d["name"] = ""; }, "name: must have"},
      {[](json& d) {
         d["symbol_names"] = {"a", "b"};
       },
       "symbol_names: has 2 names, expected 3"},
      {[](json& d) { d["source_names"] = {"a"}; }, "source_names: has 1 names, expected 2"},
      {[](json& d) { d["context_names"] = json::array(); }, "context_names: has 0 names"},
      {[](json& d) { d["context_names"] = {""}; }, "context_names[0]: is empty"},
      {[](json& d) {
         d["true_weights"] = {1.0, 2.0};
       },
       "true_weights: has 2 entries"},
      {[](json& d) {
         d.erase("observation_model");
         d.erase("symbol_names");
         d.erase("source_names");
       },
       "sensor: needs observation_model"},
      {[](json& d) { d.erase("true_weights"); }, "sensor: needs true_weights"},
      {[](json& d) { d["sensor"]["subject_observation"][1][3] = 0.3; },
       "sensor.subject_observation[0]: its row's probabilities sum to"},
      {[](json& d) { d["sensor"]["subject_observation"][0][2] = 3; }, "sensor.subject_observation[0][2]"},
      {[](json& d) { d["sensor"]["subject_observation"][0][0] = 5; }, "sensor.subject_observation[0][0]"},
      {[](json& d) {
         d["sensor"]["subject_observation"][1] = {0, 0, 0, 0.2};
       },
       "sensor.subject_observation[1]: repeats"},
      {[](json& d) {
         d["sensor"]["subject_observation"][0] = {0, 0, 0};
       },
       "sensor.subject_observation[0]"},
      {[](json& d) {
         d["sensor"]["confounder_observation"][0] = {1, 2, 1.0};
       },
       "sensor.confounder_observation[0][0]"},
      {[](json& d) { d["sensor"]["confounder_observation"][0][2] = -0.5; }, "sensor.confounder_observation[0][2]"},
      {[](json& d) { d["sensor"]["eta"] = "perfect"; }, "sensor.eta: expected \"plausible\", \"uniform\" or \"true\""},
      {[](json& d) { d["sensor"]["occlusion"] = 1.0; }, "sensor.occlusion: must be below 1"},
      {[](json& d) { d["sensor"]["observations_per_step"] = -1; }, "sensor.observations_per_step"},
      {[](json& d) { d["sensor"]["observations_per_step"] = 0; }, "sensor.observations_per_step"},
      {[](json& d) {
         d["sensor"]["trajectories"] = 100000;
         d["sensor"]["length"] = 100000;
       },
       "sensor: (trajectories + controlled_trajectories) * length * observations_per_step is"},
      {[](json& d) { d["sensor"]["trajectories"] = 0; }, "sensor.trajectories"},
      {[](json& d) { d["sensor"]["length"] = "ten"; }, "sensor.length"},
      {[](json& d) { d["sensor"]["controlled_trajectories"] = 0; }, "sensor.controlled_trajectories"},
      {[](json& d) { d["mdp"]["transitions"][0][3] = 0.5; }, "mdp.transitions"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    json doc = tiny_domain();
    cases[i].first(doc);
    try {
      parse(doc);
      ADD_FAILURE() << "case " << i << " was accepted";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(cases[i].second), std::string::npos) << "case " << i << ": " << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
  try {
    parse_domain("{\"mdp\": ", "x");
    ADD_FAILURE() << "malformed JSON accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("malformed JSON"), std::string::npos);
  }
}

TEST(DomainFile, ExamplesAreValid) {
  for (const char* name : {"warehouse.json", "corridor.json"}) {
    std::vector<std::string> warnings;
    const DomainSpec d = read_domain_file(std::string(HBIRL_SOURCE_DIR) + "/examples/" + name, &warnings);
    EXPECT_TRUE(warnings.empty()) << name;
    EXPECT_GT(d.mdp.num_states, 0);
  }
  const DomainSpec w = read_domain_file(std::string(HBIRL_SOURCE_DIR) + "/examples/warehouse.json");
  EXPECT_EQ(w.name, "warehouse");
  ASSERT_TRUE(w.sensor.has_value());
  EXPECT_EQ(w.num_sources(), 3);
}

}  // namespace
}  // namespace hbirl
