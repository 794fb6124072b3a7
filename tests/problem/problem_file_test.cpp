#include "problem/problem_file.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <ctime>
#include <functional>
#include <numeric>
#include <sstream>

#include "learner/input_error.hpp"
#include "problem/json_format.hpp"

namespace hbirl {
namespace {

using nlohmann::json;

// A minimal problem file (format: docs/files.md "Problem files"), extended with names and a terminal-free 3-state MDP.
json spec_example() {
  return json::parse(R"({
    "mdp": {
      "num_states": 3, "num_actions": 2, "num_features": 2,
      "transitions": [[0, 0, 1, 1.0], [0, 1, 2, 0.7], [0, 1, 0, 0.3], [1, 0, 1, 1.0],
                      [1, 1, 2, 1.0], [2, 0, 2, 1.0], [2, 1, 0, 1.0]],
      "start": [[0, 1.0]],
      "features": [[1, 0, 0, 1.0], [2, 1, 1, 1.0]],
      "discount": 0.95
    },
    "observation_model": {
      "num_symbols": 4, "num_confounders": 2,
      "subject_alpha": [[0, 0, 3, 12.0]], "subject_alpha_default": 1.0,
      "confounder_alpha": [[0, 1, 5.0]], "confounder_alpha_default": 1.0,
      "learn": true, "c": 0.1
    },
    "demonstration": [
      { "steps": [
          { "observations": [[3, [0.6, 0.2, 0.2]], [1, [0.1, 0.8, 0.1]]] },
          { "observations": [] }
        ],
        "truth": [[0, 1], [2, 0]] }
    ],
    "true_weights": [0.0, 1.0]
  })");
}

// Parses `doc` after `mutate` and expects an InputError naming `field` whose message
// contains `fragment`.
void expect_error(const std::function<void(json&)>& mutate, const std::string& field, const std::string& fragment) {
  json doc = spec_example();
  mutate(doc);
  try {
    parse_problem(doc.dump());
    ADD_FAILURE() << "accepted; expected an error at " << field;
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_NE(e.message().find(fragment), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line: " << e.what();
  }
}

TEST(ProblemFile, SpecExampleParses) {
  std::vector<std::string> warnings;
  const Problem p = parse_problem(spec_example().dump(), &warnings);
  EXPECT_TRUE(warnings.empty());
  EXPECT_EQ(p.mdp.num_states, 3);
  EXPECT_EQ(p.mdp.num_features(), 2);
  EXPECT_DOUBLE_EQ(p.mdp.transitions.coeff(p.mdp.pair(0, 1), 2), 0.7);
  EXPECT_DOUBLE_EQ(p.mdp.features(p.mdp.pair(2, 1), 1), 1.0);
  ASSERT_TRUE(p.observation_model);
  EXPECT_DOUBLE_EQ(p.observation_model->subject_alpha(p.mdp.pair(0, 0), 3), 12.0);
  EXPECT_DOUBLE_EQ(p.observation_model->subject_alpha(p.mdp.pair(1, 1), 2), 1.0);
  EXPECT_DOUBLE_EQ(p.observation_model->confounder_alpha(0, 1), 5.0);
  ASSERT_EQ(p.demonstration.size(), 1u);
  const ObservedTrajectory& steps = *p.demonstration[0].steps;
  EXPECT_EQ(steps.length(), 2);
  EXPECT_EQ(steps.observations_at(0), 2);
  EXPECT_EQ(steps.observations_at(1), 0);  // occluded
  EXPECT_EQ(steps.symbols[1], 1);
  EXPECT_DOUBLE_EQ(steps.eta(1, 1), 0.8);
  EXPECT_EQ(*p.demonstration[0].truth, (Trajectory{{0, 1}, {2, 0}}));
  EXPECT_EQ(*p.true_weights, Eigen::Vector2d(0.0, 1.0));
}

TEST(ProblemFile, RoundTripsThroughJson) {
  const Problem p = parse_problem(spec_example().dump());
  const Problem q = parse_problem(problem_to_json(p).dump());
  EXPECT_TRUE(p.mdp.transitions.isApprox(q.mdp.transitions, 0.0));
  EXPECT_EQ(p.mdp.features, q.mdp.features);
  EXPECT_EQ(p.mdp.start, q.mdp.start);
  EXPECT_EQ(p.observation_model->subject_alpha, q.observation_model->subject_alpha);
  EXPECT_EQ(p.observation_model->confounder_alpha, q.observation_model->confounder_alpha);
  EXPECT_EQ(p.demonstration[0].steps->eta, q.demonstration[0].steps->eta);
  EXPECT_EQ(p.demonstration[0].steps->step_begin, q.demonstration[0].steps->step_begin);
  EXPECT_EQ(*p.demonstration[0].truth, *q.demonstration[0].truth);
}

// "name": what hbirl publish's episodes carry (the domain's name), read with a domain
// file's rules and written back; a file without one has none (publish uses its stem).
TEST(ProblemFile, TheDomainNameRoundTripsAndIsChecked) {
  EXPECT_EQ(parse_problem(spec_example().dump()).name, "");
  json d = spec_example();
  d["name"] = "vacuum-2.b";
  std::vector<std::string> warnings;
  const Problem p = parse_problem(d.dump(), &warnings);
  EXPECT_TRUE(warnings.empty()) << warnings.front();  // a known key, not "ignored"
  EXPECT_EQ(p.name, "vacuum-2.b");
  EXPECT_EQ(parse_problem(problem_to_json(p).dump()).name, "vacuum-2.b");
  expect_error([](json& doc) { doc["name"] = "two words"; }, "name", "letters, digits");
  expect_error([](json& doc) { doc["name"] = ""; }, "name", "1 to 64");
  expect_error([](json& doc) { doc["name"] = std::string(65, 'a'); }, "name", "1 to 64");
  expect_error([](json& doc) { doc["name"] = 3; }, "name", "");
}

// "context_names": the sensor's contexts by name (learned eta is reported by them), read,
// checked and written back.
TEST(ProblemFile, ContextNamesRoundTripAndAreChecked) {
  EXPECT_TRUE(parse_problem(spec_example().dump()).context_names.empty());
  json d = spec_example();
  d["context_names"] = {"tracked person", "unknown blob"};
  std::vector<std::string> warnings;
  const Problem p = parse_problem(d.dump(), &warnings);
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  EXPECT_EQ(p.context_names, (std::vector<std::string>{"tracked person", "unknown blob"}));
  EXPECT_EQ(parse_problem(problem_to_json(p).dump()).context_names, p.context_names);
  expect_error([](json& doc) { doc["context_names"] = json::array(); }, "context_names", "give 1 to 65536");
  expect_error([](json& doc) { doc["context_names"] = {"a", ""}; }, "context_names[1]", "is empty");
  expect_error([](json& doc) { doc["context_names"] = {"a", 3}; }, "context_names[1]", "");
  expect_error([](json& doc) { doc["context_names"] = "a"; }, "context_names", "");
}

// The spec example with a terminal state 3 that (2, 0) enters, an end sensor of two
// symbols and a trajectory that says what was seen of its end (docs/files.md "Problem files").
json with_end_sensor() {
  json d = spec_example();
  d["mdp"]["num_states"] = 4;
  d["mdp"]["terminal"] = {3};
  d["mdp"]["transitions"][5] = {2, 0, 3, 1.0};
  d["observation_model"]["end_sensor"] = json::parse(R"({"num_symbols": 2, "alpha": [[3, 0, 9.0]]})");
  d["demonstration"][0]["end_symbols"] = {0, 0, 1};
  d["demonstration"][0]["end_state"] = 3;
  return d;
}

// write_problem streams what format_json(problem_to_json(...)) writes, byte for byte: with
// fields before and after, with an end sensor, with true steps, and with no demonstration.
TEST(ProblemFile, StreamedTextIsTheFormattedDocument) {
  const auto streamed = [](const Problem& p, const nlohmann::ordered_json& before,
                           const nlohmann::ordered_json& after) {
    std::ostringstream out;
    write_problem(out, p, before, after);
    return out.str();
  };
  const auto whole = [](const Problem& p, const nlohmann::ordered_json& before, const nlohmann::ordered_json& after) {
    nlohmann::ordered_json doc = before.is_object() ? before : nlohmann::ordered_json::object();
    doc.update(problem_to_json(p));
    if (after.is_object()) doc.update(after);
    return format_json(doc);
  };
  const nlohmann::ordered_json comment = {{"comment", "first"}};
  const nlohmann::ordered_json last = {{"note", "last"}, {"more", {1, 2}}};
  for (const json& d : {spec_example(), with_end_sensor()}) {
    const Problem p = parse_problem(d.dump());
    ASSERT_FALSE(p.demonstration.empty());
    EXPECT_EQ(streamed(p, {}, {}), format_json(problem_to_json(p)));
    EXPECT_EQ(streamed(p, comment, {}), whole(p, comment, {}));
    EXPECT_EQ(streamed(p, {}, last), whole(p, {}, last));
    Problem none = p;
    none.demonstration.clear();
    EXPECT_EQ(streamed(none, comment, last), whole(none, comment, last));
    EXPECT_EQ(parse_problem(streamed(p, comment, last)).demonstration.size(), p.demonstration.size());
    if (d == spec_example()) {
      // Past the writer's 1 MB flush (a piece written mid-document), and a trajectory with
      // nothing to say (an object all the same). Once: 16,384 trajectories cost seconds
      // under the sanitizers.
      Problem many = p;
      for (int copy = 0; copy < 14; ++copy) {
        const std::vector<DemonstratedTrajectory> more = many.demonstration;
        many.demonstration.insert(many.demonstration.end(), more.begin(), more.end());
      }
      many.demonstration.push_back(DemonstratedTrajectory{});
      const std::string text = streamed(many, comment, last);
      EXPECT_GT(text.size(), size_t{1} << 20);
      EXPECT_EQ(text, whole(many, comment, last));
    }
    // A key that would appear twice is the caller's mistake, refused before a byte is written.
    for (const std::string k : {"demonstration", "mdp", "true_weights"}) {
      std::ostringstream out;
      EXPECT_THROW(write_problem(out, p, {{k, 1}}, {}), std::logic_error) << k;
      EXPECT_TRUE(out.str().empty()) << k;
    }
    std::ostringstream twice;
    EXPECT_THROW(write_problem(twice, p, comment, comment), std::logic_error);
  }
}

TEST(ProblemFile, EndSensorAndWhatWasSeenOfTheEndRoundTrip) {
  std::vector<std::string> warnings;
  const Problem p = parse_problem(with_end_sensor().dump(), &warnings);
  EXPECT_TRUE(warnings.empty());
  const ObservationPrior& prior = *p.observation_model;
  ASSERT_EQ(prior.num_end_symbols(), 2);
  EXPECT_DOUBLE_EQ(prior.end_alpha(3, 0), 9.0);
  EXPECT_DOUBLE_EQ(prior.end_alpha(3, 1), 1.0);                        // alpha_default
  EXPECT_DOUBLE_EQ(prior.end_alpha.topRows(3).cwiseAbs().sum(), 0.0);  // rows never used
  const ObservedTrajectory& steps = *p.demonstration[0].steps;
  EXPECT_EQ(steps.end_symbols, (std::vector<int>{0, 0, 1}));
  EXPECT_EQ(steps.end_state, 3);
  const Problem q = parse_problem(problem_to_json(p).dump());
  EXPECT_EQ(q.observation_model->end_alpha, prior.end_alpha);
  EXPECT_EQ(q.demonstration[0].steps->end_symbols, steps.end_symbols);
  EXPECT_EQ(q.demonstration[0].steps->end_state, 3);
  EXPECT_EQ(problem_to_json(q).dump(), problem_to_json(p).dump());
  // alpha_default is the pseudo-count of a state nobody counted reports of (weighed_end_prior).
  json d = with_end_sensor();
  d["observation_model"]["end_sensor"]["alpha_default"] = 5.0;
  const Problem five = parse_problem(d.dump());
  EXPECT_DOUBLE_EQ(five.observation_model->end_alpha_base, 5.0);
  EXPECT_DOUBLE_EQ(parse_problem(problem_to_json(five).dump()).observation_model->end_alpha_base, 5.0);
}

TEST(ProblemFile, WhatWasSeenOfTheEndIsChecked) {
  auto expect_end_error = [](const std::function<void(json&)>& mutate, const std::string& field,
                             const std::string& fragment) {
    expect_error(
        [&](json& d) {
          d = with_end_sensor();
          mutate(d);
        },
        field, fragment);
  };
  expect_end_error([](json& d) { d["observation_model"].erase("end_sensor"); }, "demonstration[0].end_symbols",
                   "observation_model has no \"end_sensor\"");
  expect_end_error([](json& d) { d["demonstration"][0]["end_symbols"][1] = 2; }, "demonstration[0].end_symbols[1]", "");
  expect_end_error([](json& d) { d["demonstration"][0]["end_state"] = 1; }, "demonstration[0].end_state",
                   "state 1 is not terminal");
  expect_end_error([](json& d) { d["demonstration"][0]["controlled"] = true; }, "demonstration[0].end_state",
                   "a controlled run's end is not used");
  expect_end_error([](json& d) { d["demonstration"][0]["ends_in_terminal"] = false; }, "demonstration[0].end_state",
                   "does not end in a terminal state");
  expect_end_error([](json& d) { d["demonstration"][0].erase("steps"); }, "demonstration[0].end_state",
                   "needs \"steps\"");
  expect_end_error(
      [](json& d) {
        d["observation_model"]["end_sensor"]["alpha"] = {{1, 0, 2.0}};
      },
      "observation_model.end_sensor.alpha[0][0]", "state 1 is not terminal");
  expect_end_error(
      [](json& d) {
        d["observation_model"]["end_sensor"]["alpha"] = {{3, 0, 0.0}, {3, 1, 0.0}};
      },
      "observation_model.end_sensor.alpha", "alpha of terminal state 3 sums to 0");
  expect_error([](json& d) { d["observation_model"]["end_sensor"] = json::parse(R"({"num_symbols": 2})"); },
               "observation_model.end_sensor", "the MDP has no terminal states");
}

// An MDP written and read back is the same MDP to the bit, even where its start
// distribution sums to 1 only up to rounding (25 x 0.04 in doubles: reading it used to
// renormalise every probability by an ulp, so a recorded run's exported problem learned
// another theta in the 8th digit).
TEST(ProblemFile, AStartDistributionThatSumsToOneUpToRoundingReadsBackBitForBit) {
  Problem p;
  std::vector<TransitionEntry> transitions;
  for (int s = 0; s < 25; ++s) transitions.push_back({s, 0, (s + 1) % 25, 1.0});
  p.mdp = make_mdp(25, 1, 1, transitions, {{0, 0, 0, 1.0}}, Eigen::VectorXd::Constant(25, 1.0 / 25.0), {}, 0.9);
  ASSERT_NE(std::accumulate(p.mdp.start.begin(), p.mdp.start.end(), 0.0), 1.0);  // the case in point (summed in order)
  DemonstratedTrajectory walk;
  walk.truth = Trajectory{{0, 0}, {1, 0}};
  p.demonstration.push_back(walk);
  const Problem q = parse_problem(problem_to_json(p).dump());
  EXPECT_EQ(q.mdp.start, p.mdp.start);
  // A sum off by more than rounding (within the file tolerance) is still renormalised.
  nlohmann::json doc = problem_to_json(p);
  doc["mdp"]["start"][0][1] = 0.04 + 1e-9;
  EXPECT_NEAR(parse_problem(doc.dump()).mdp.start.sum(), 1.0, 1e-15);
}

// The observation model's learning options: defaults, every key, the round trip, and one
// line naming the field for each bad value.
TEST(ProblemFile, ObservationModelLearningOptions) {
  const Problem defaults = parse_problem(spec_example().dump());
  EXPECT_EQ(defaults.observation_model->update, AlphaUpdate::kPosterior);
  EXPECT_TRUE(defaults.observation_model->automatic_strength);
  EXPECT_TRUE(defaults.observation_model->learn_eta);
  EXPECT_FALSE(defaults.observation_model->tie_actions);
  EXPECT_FALSE(problem_to_json(defaults)["observation_model"].contains("tie_actions"));  // files stay as they were
  json d = spec_example();
  d["observation_model"]["update"] = "paper";
  d["observation_model"]["prior_strength"] = 0.5;
  d["observation_model"]["subject_alpha_default"] = 2.0;
  const Problem paper = parse_problem(d.dump());
  EXPECT_EQ(paper.observation_model->update, AlphaUpdate::kPaper);
  EXPECT_FALSE(paper.observation_model->learn_eta);  // the paper's update takes eta as given
  EXPECT_FALSE(paper.observation_model->automatic_strength);
  EXPECT_EQ(paper.observation_model->strength, 0.5);
  EXPECT_EQ(paper.observation_model->subject_alpha_base, 2.0);
  d["observation_model"]["update"] = "posterior";
  d["observation_model"]["learn_eta"] = false;
  d["observation_model"]["eta_prior_strength"] = 25.0;
  d["observation_model"]["tie_actions"] = true;
  const Problem p = parse_problem(d.dump());
  const Problem q = parse_problem(problem_to_json(p).dump());
  for (const Problem* x : {&p, &q}) {
    EXPECT_EQ(x->observation_model->update, AlphaUpdate::kPosterior);
    EXPECT_FALSE(x->observation_model->learn_eta);
    EXPECT_EQ(x->observation_model->eta_strength, 25.0);
    EXPECT_EQ(x->observation_model->strength, 0.5);
    EXPECT_EQ(x->observation_model->subject_alpha_base, 2.0);
    EXPECT_TRUE(x->observation_model->tie_actions);
  }
  expect_error([](json& e) { e["observation_model"]["tie_actions"] = 1; }, "observation_model.tie_actions",
               "true or false");
  expect_error([](json& e) { e["observation_model"]["update"] = "bayes"; }, "observation_model.update",
               "expected \"posterior\" or \"paper\"");
  expect_error([](json& e) { e["observation_model"]["prior_strength"] = "high"; }, "observation_model.prior_strength",
               "expected \"auto\" or a positive number");
  expect_error([](json& e) { e["observation_model"]["prior_strength"] = 0.0; }, "observation_model.prior_strength", "");
  expect_error([](json& e) { e["observation_model"]["eta_prior_strength"] = -1.0; },
               "observation_model.eta_prior_strength", "");
  expect_error([](json& e) { e["observation_model"]["learn_eta"] = "yes"; }, "observation_model.learn_eta",
               "true or false");
}

// Contexts ([symbol, eta, context]) and the unlisted catch-all round-trip through the
// file; their bad values get one line naming the field.
TEST(ProblemFile, ContextsAndUnlistedSource) {
  json d = spec_example();
  d["observation_model"]["unlisted_source"] = {{"eta", 0.2}};
  d["demonstration"][0]["steps"][0]["observations"] =
      json::parse(R"([[3, [0.6, 0.2, 0.2], 4], [1, [0.1, 0.8, 0.1], 0]])");
  const Problem p = parse_problem(d.dump());
  const Problem q = parse_problem(problem_to_json(p).dump());
  for (const Problem* x : {&p, &q}) {
    EXPECT_EQ(x->observation_model->unlisted_eta, 0.2);
    EXPECT_FALSE(x->observation_model->unlisted_added);  // the learner adds the catch-all, not the file
    EXPECT_EQ(x->demonstration[0].steps->contexts, (std::vector<int>{4, 0}));
  }
  const Problem plain = parse_problem(spec_example().dump());
  EXPECT_TRUE(plain.demonstration[0].steps->contexts.empty());
  EXPECT_EQ(plain.observation_model->unlisted_eta, 0.0);
  const auto observations = [](json& e) -> json& { return e["demonstration"][0]["steps"][0]["observations"]; };
  expect_error([&](json& e) { observations(e)[0].push_back(-1); }, "demonstration[0].steps[0].observations[0][2]",
               "integer");
  expect_error([&](json& e) { observations(e)[0].push_back(1 << 16); }, "demonstration[0].steps[0].observations[0][2]",
               "");
  expect_error([&](json& e) { observations(e)[0].push_back(0.5); }, "demonstration[0].steps[0].observations[0][2]",
               "integer");
  expect_error([&](json& e) { observations(e)[1].push_back(2); }, "demonstration[0].steps[0].observations[1]",
               "has a context, the trajectory's earlier observations none");
  expect_error([&](json& e) { observations(e)[0].push_back(2); }, "demonstration[0].steps[0].observations[1]",
               "has no context");
  for (double bad : {0.0, 1.0, -0.1, 2.0}) {
    expect_error(
        [&](json& e) {
          e["observation_model"]["unlisted_source"] = {{"eta", bad}};
        },
        "observation_model.unlisted_source.eta", "(0, 1)");
  }
  expect_error([](json& e) { e["observation_model"]["unlisted_source"] = json::object(); },
               "observation_model.unlisted_source.eta", "missing");
  expect_error([](json& e) { e["observation_model"]["eta_prior_strength"] = 0.0; },
               "observation_model.eta_prior_strength", "(0, 1e12]");
  // learn_eta said true with nothing to learn: one source, or no observations.
  expect_error(
      [](json& e) {
        e["observation_model"]["learn_eta"] = true;
        e["observation_model"]["num_confounders"] = 0;
        e["observation_model"].erase("confounder_alpha");
        e["demonstration"][0]["steps"][0]["observations"] = json::parse("[[3, [1.0]]]");
      },
      "observation_model.learn_eta", "one source");
  expect_error(
      [](json& e) {
        e["observation_model"]["learn_eta"] = true;
        e["demonstration"][0]["steps"][0]["observations"] = json::array();
      },
      "observation_model.learn_eta", "no demonstrated step has observations");
}

TEST(ProblemFile, MalformedJson) {
  try {
    parse_problem("{\n  \"mdp\": {,\n}");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(e.message().find("malformed JSON"), std::string::npos);
    EXPECT_NE(e.message().find("line 2, column 11"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_problem(""), InputError);
  EXPECT_THROW(parse_problem("[1, 2]"), InputError);
}

TEST(ProblemFile, WrongTypes) {
  expect_error([](json& d) { d["mdp"]["num_states"] = "3"; }, "mdp.num_states", "expected an integer");
  expect_error([](json& d) { d["mdp"]["num_states"] = 2.5; }, "mdp.num_states", "expected an integer");
  expect_error([](json& d) { d["mdp"]["transitions"] = json::object(); }, "mdp.transitions", "expected an array");
  expect_error(
      [](json& d) {
        d["mdp"]["transitions"][1] = {0, 1, 2};
      },
      "mdp.transitions[1]", "expected [state, action, next_state, probability]");
  expect_error([](json& d) { d["mdp"]["transitions"][1][3] = "0.7"; }, "mdp.transitions[1][3]", "expected a number");
  expect_error([](json& d) { d["observation_model"]["learn"] = 1; }, "observation_model.learn", "true or false");
  expect_error([](json& d) { d["demonstration"][0]["steps"][0]["observations"][0] = 3; },
               "demonstration[0].steps[0].observations[0]", "expected [symbol, [eta...]]");
  expect_error([](json& d) { d["demonstration"] = json::object(); }, "demonstration", "expected an array");
  expect_error([](json& d) { d["mdp"]["state_names"] = {"a", 2, "c"}; }, "mdp.state_names[1]", "expected a string");
}

TEST(ProblemFile, MissingRequiredFields) {
  expect_error([](json& d) { d["mdp"].erase("transitions"); }, "mdp.transitions", "missing");
  expect_error([](json& d) { d.erase("demonstration"); }, "demonstration", "missing");
  expect_error([](json& d) { d["demonstration"][0]["steps"][1].erase("observations"); },
               "demonstration[0].steps[1].observations", "missing");
}

TEST(ProblemFile, ProbabilitiesNotSummingToOne) {
  expect_error([](json& d) { d["mdp"]["transitions"][1][3] = 0.6; }, "mdp.transitions[1]",
               "probabilities for (s=0, a=1) sum to 0.9");
  expect_error([](json& d) { d["mdp"]["start"] = {{0, 0.5}, {1, 0.4}}; }, "mdp.start", "sum to 0.9");
  expect_error(
      [](json& d) {
        d["demonstration"][0]["steps"][0]["observations"][0][1] = {0.6, 0.2, 0.1};
      },
      "demonstration[0].steps[0].observations[0]", "eta sums to 0.9");
  expect_error([](json& d) { d["mdp"]["transitions"].erase(0); }, "mdp.transitions", "no entries for (s=0, a=0)");
}

TEST(ProblemFile, RoundedProbabilitiesAreRenormalised) {
  json d = spec_example();
  d["mdp"]["transitions"][1][3] = 0.6999995;
  const Problem p = parse_problem(d.dump());
  EXPECT_NEAR(p.mdp.transitions.coeff(p.mdp.pair(0, 1), 2) + p.mdp.transitions.coeff(p.mdp.pair(0, 1), 0), 1.0, 1e-15);
}

TEST(ProblemFile, NonFiniteNumbers) {
  // JSON has no NaN or infinity: they arrive as syntax errors or overflowing literals.
  json d = spec_example();
  std::string text = d.dump();
  const std::string needle = "0.7";
  std::string nan_text = text;
  nan_text.replace(nan_text.find(needle), needle.size(), "NaN");
  EXPECT_THROW(parse_problem(nan_text), InputError);
  // An eta entry that is not a number (a string "NaN") names the field.
  expect_error(
      [](json& x) {
        x["demonstration"][0]["steps"][0]["observations"][0][1] = {"NaN", 0.2, 0.2};
      },
      "demonstration[0].steps[0].observations[0][1][0]", "expected a number");
  std::string eta_text = text;
  const std::string eta = "[0.6,0.2,0.2]";
  ASSERT_NE(eta_text.find(eta), std::string::npos);
  eta_text.replace(eta_text.find(eta), eta.size(), "[NaN,0.2,0.2]");
  EXPECT_THROW(parse_problem(eta_text), InputError);
  std::string inf_text = text;
  inf_text.replace(inf_text.find(needle), needle.size(), "1e999");
  try {
    parse_problem(inf_text);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(e.message().find("NaN and infinity are not JSON numbers"), std::string::npos) << e.what();
  }
}

TEST(ProblemFile, NegativeValues) {
  expect_error([](json& d) { d["mdp"]["transitions"][1][3] = -0.7; }, "mdp.transitions[1][3]",
               "expected a number in [0, 1]");
  expect_error([](json& d) { d["mdp"]["num_states"] = -3; }, "mdp.num_states", "expected an integer in [1,");
  expect_error([](json& d) { d["observation_model"]["subject_alpha"][0][3] = -1.0; },
               "observation_model.subject_alpha[0][3]", "expected a number in [0,");
  expect_error(
      [](json& d) {
        d["demonstration"][0]["steps"][0]["observations"][1][1] = {-0.1, 1.0, 0.1};
      },
      "demonstration[0].steps[0].observations[1][1][0]", "expected a number in [0, 1]");
  expect_error([](json& d) { d["mdp"]["discount"] = 0.9999999999999999; }, "mdp.discount", "got 0.99999999999999989");
  expect_error([](json& d) { d["mdp"]["num_states"] = 1 << 20; }, "mdp.num_states",
               "is 1048576, but the file lists only");
  expect_error([](json& d) { d["mdp"]["features"][0][3] = 1.7e308; }, "mdp.features[0][3]",
               "expected a number in [-1000000, 1000000]");
  expect_error([](json& d) { d["true_weights"][0] = -1e308; }, "true_weights[0]",
               "expected a number in [-1000000, 1000000]");
  expect_error([](json& d) { d["mdp"]["discount"] = -0.5; }, "mdp.discount", "expected a number in [0, 0.999999]");
}

TEST(ProblemFile, OutOfRangeIndices) {
  expect_error([](json& d) { d["mdp"]["transitions"][0][2] = 3; }, "mdp.transitions[0][2]",
               "expected an integer in [0, 2]");
  expect_error([](json& d) { d["mdp"]["features"][0][2] = 2; }, "mdp.features[0][2]", "expected an integer in [0, 1]");
  expect_error([](json& d) { d["demonstration"][0]["steps"][0]["observations"][0][0] = 4; },
               "demonstration[0].steps[0].observations[0][0]", "expected an integer in [0, 3]");
  expect_error(
      [](json& d) {
        d["demonstration"][0]["truth"][1] = {5, 0};
      },
      "demonstration[0].truth[1][0]", "expected an integer in [0, 2]");
  expect_error([](json& d) { d["observation_model"]["confounder_alpha"][0][0] = 2; },
               "observation_model.confounder_alpha[0][0]", "expected an integer in [0, 1]");
  expect_error([](json& d) { d["mdp"]["terminal"] = {7}; }, "mdp.terminal[0]", "expected an integer in [0, 2]");
}

TEST(ProblemFile, InconsistentContent) {
  expect_error(
      [](json& d) {
        d["demonstration"][0]["steps"][0]["observations"][0][1] = {0.5, 0.5};
      },
      "demonstration[0].steps[0].observations[0]", "eta has 2 entries, expected 3");
  expect_error(
      [](json& d) {
        d["demonstration"][0]["truth"] = {{0, 1}, {1, 0}};
      },
      "demonstration[0].truth[1]", "state 1 cannot follow (s=0, a=1)");
  expect_error(
      [](json& d) {
        d["demonstration"][0]["truth"] = {{0, 1}};
      },
      "demonstration[0].truth", "has 1 steps but \"steps\" has 2");
  expect_error([](json& d) { d["true_weights"] = {1.0}; }, "true_weights", "has 1 entries, expected 2");
  expect_error(
      [](json& d) {
        d["mdp"]["transitions"].push_back({0, 0, 1, 0.0});
      },
      "mdp.transitions[7]", "duplicate transition (also given at index 0)");
  expect_error([](json& d) { d["mdp"]["terminal"] = {0}; }, "mdp.start[0]", "start state 0 is terminal");
  expect_error([](json& d) { d.erase("observation_model"); }, "demonstration[0].steps",
               "has observations but the file has no observation_model");
  expect_error([](json& d) { d["mdp"]["state_names"] = {"a", "b"}; }, "mdp.state_names", "has 2 names, expected 3");
}

// Tuple lists are checked as they are read (json_document.hpp): a repeat, or an element of
// the wrong shape, is refused where it is, before the rest of the file is even parsed --
// here, a file cut short after it, which would otherwise be "malformed JSON".
TEST(ProblemFile, TupleListsAreCheckedAsTheyAreRead) {
  const std::string text = spec_example().dump();
  const auto cut_after = [&text](const std::string& key, const std::string& elements) {
    const std::string list = "\"" + key + "\":[";
    return text.substr(0, text.find(list) + list.size()) + elements;  // no closing bracket, nothing after
  };
  const auto error_of = [](const std::string& doc) -> std::string {
    try {
      parse_problem(doc);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(accepted)";
  };
  EXPECT_EQ(error_of(cut_after("transitions", "[0,0,1,1.0],[0,0,1,1.0],[0,1")),
            "mdp.transitions[1]: duplicate transition (also given at index 0)");
  EXPECT_EQ(error_of(cut_after("transitions", "[0,0,1,1.0],[0,1,2,0.5],[0,1,0,0.5],[0,1,2,0.5],")),
            "mdp.transitions[3]: duplicate transition (also given at index 1)");
  EXPECT_EQ(error_of(cut_after("transitions", "[0,0,1,1.0],[0,1,2],")),
            "mdp.transitions[1]: expected [state, action, next_state, probability], got an array of 3");
  EXPECT_EQ(error_of(cut_after("features", "[1,0,0,1.0],[1.0,0,0,2.0],")),
            "mdp.features[1]: duplicate feature entry (also given at index 0)");
  EXPECT_EQ(error_of(cut_after("start", "[0,0.5],[0,0.5]")),
            "mdp.start[1]: duplicate start state (also given at index 0)");
  EXPECT_EQ(error_of(cut_after("truth", "[0,1],7")),
            "demonstration[0].truth[1]: expected [state, action], got the number 7");
}

// No problem or domain file nests deeper than 8 arrays and objects; each level held costs
// ~100 bytes for a byte of text (50 MB of "[" took 3.7 GB before "malformed JSON").
// Refused at 64, where it is, before the end of the text is reached; inside a key the
// format does not know nothing is held, so there any depth only warns.
TEST(ProblemFile, DeepNestingIsRefusedWhereItIs) {
  try {
    parse_problem("{\"mdp\":" + std::string(100, '['));
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.message(), "nested more than 64 arrays and objects deep: not a problem or domain file") << e.what();
    EXPECT_EQ(e.field().rfind("mdp[0][0]", 0), 0u) << e.what();
  }
  std::string text = spec_example().dump();
  text.insert(1, "\"deep\":" + std::string(1000, '[') + std::string(1000, ']') + ",");
  std::vector<std::string> warnings;
  EXPECT_NO_THROW(parse_problem(text, &warnings));
  EXPECT_EQ(warnings, std::vector<std::string>{"deep: unknown key, ignored"});
}

// The first repeat in the file's order is the one named (here (0,1,2) at 1 and 7, then
// (0,1,0) at 2 and 8), as the parser finds it; the reader's own check afterwards names the
// same one (it used to name the smallest repeated key's: index 8).
TEST(ProblemFile, TheFirstRepeatInTheFilesOrderIsNamed) {
  expect_error(
      [](json& d) {
        d["mdp"]["transitions"].push_back({0, 1, 2, 0.1});
        d["mdp"]["transitions"].push_back({0, 1, 0, 0.1});
      },
      "mdp.transitions[7]", "duplicate transition (also given at index 1)");
}

// Reading is linear in a trajectory's length: each step is an object, and the parser's
// callback used to scan every earlier step when one ended (40,000 steps 0.4 s, 160,000
// 4.8 s). Compared, not timed: 8 times the steps may take at most 20 times the CPU time
// (linear is 8; the old reader took 40 or more).
TEST(ProblemFile, ReadingIsLinearInATrajectorysLength) {
  const auto problem_with = [](int steps) {
    json d = spec_example();
    std::string text = d.dump();
    std::string trajectory = R"({"ends_in_terminal":false,"steps":[)";
    for (int t = 0; t < steps; ++t) trajectory += std::string(t ? "," : "") + R"({"observations":[[3,[0.6,0.2,0.2]]]})";
    trajectory += "]}";
    const std::string list = "\"demonstration\":[";
    text.insert(text.find(list) + list.size(), trajectory + ",");
    return text;
  };
  const auto cpu_seconds = [](const std::string& text) {
    double best = 1e300;
    for (int repeat = 0; repeat < 5; ++repeat) {
      timespec start{}, end{};
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &start);
      const Problem p = parse_problem(text);
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &end);
      EXPECT_EQ(p.demonstration.size(), 2u);
      best = std::min(best, static_cast<double>(end.tv_sec - start.tv_sec) +
                                1e-9 * static_cast<double>(end.tv_nsec - start.tv_nsec));
    }
    return best;
  };
  const double short_one = cpu_seconds(problem_with(10000));
  const double long_one = cpu_seconds(problem_with(80000));
  EXPECT_LT(long_one, 20.0 * short_one) << "10,000 steps " << short_one << " s, 80,000 steps " << long_one << " s";
}

TEST(ProblemFile, EmptyDemonstration) {
  expect_error([](json& d) { d["demonstration"] = json::array(); }, "demonstration", "is empty");
  expect_error([](json& d) { d["demonstration"][0] = json::object(); }, "demonstration[0]", "has neither");
  expect_error(
      [](json& d) {
        d["demonstration"][0]["steps"] = json::array();
        d["demonstration"][0].erase("truth");
      },
      "demonstration[0].steps", "is empty");
  expect_error([](json& d) { d["demonstration"][0]["truth"] = json::array(); }, "demonstration[0].truth", "is empty");
}

TEST(ProblemFile, UnknownKeysWarnButParse) {
  json d = spec_example();
  d["mdp"]["transitons"] = json::array();
  d["extra"] = 1;
  d["comment"] = "comments are fine";
  d["mdp"]["_note"] = "so are keys starting with an underscore";
  std::vector<std::string> warnings;
  EXPECT_NO_THROW(parse_problem(d.dump(), &warnings));
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0], "extra: unknown key, ignored");
  EXPECT_EQ(warnings[1], "mdp.transitons: unknown key, ignored (did you mean \"transitions\"?)");
}

TEST(ProblemFile, DefaultsAndExtensions) {
  json d = spec_example();
  d["mdp"].erase("start");
  d["mdp"].erase("discount");
  d["mdp"]["terminal"] = {1};
  d["mdp"]["transitions"] = {{0, 0, 1, 1.0}, {0, 1, 2, 0.7}, {0, 1, 0, 0.3}, {2, 0, 2, 1.0}};
  d["mdp"]["impossible_actions"] = {{2, 1}};
  d["demonstration"][0]["truth"] = {{0, 1}, {2, 0}};
  // With terminal states a trajectory ends by entering one unless it says it was cut off.
  try {
    parse_problem(d.dump());
    ADD_FAILURE() << "accepted a trajectory that cannot have ended in a terminal state";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "demonstration[0].truth");
    EXPECT_NE(e.message().find("cannot enter a terminal state"), std::string::npos);
  }
  d["demonstration"][0]["ends_in_terminal"] = false;
  const Problem p = parse_problem(d.dump());
  EXPECT_FALSE(p.demonstration[0].ends_in_terminal);
  EXPECT_FALSE(p.demonstration[0].steps->ends_in_terminal);
  EXPECT_DOUBLE_EQ(p.mdp.discount, 0.95);
  EXPECT_DOUBLE_EQ(p.mdp.start[0], 0.5);  // uniform over the non-terminal states 0 and 2
  EXPECT_DOUBLE_EQ(p.mdp.start[1], 0.0);
  EXPECT_TRUE(p.mdp.is_terminal(1));
  EXPECT_FALSE(p.mdp.available(2, 1));
  expect_error(
      [](json& x) {
        x["mdp"]["impossible_actions"] = {{0, 0}};
      },
      "mdp.transitions[0]", "which mdp.impossible_actions lists as impossible");
  expect_error([](json& x) { x["demonstration"][0]["ends_in_terminal"] = true; }, "demonstration[0].ends_in_terminal",
               "the MDP has no terminal states");
  const Problem q = parse_problem(problem_to_json(p).dump());
  EXPECT_FALSE(q.demonstration[0].ends_in_terminal);
}

TEST(ProblemFile, MissingAndUnreadableFiles) {
  try {
    read_problem_file("/nonexistent/problem.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(e.message().find("cannot open"), std::string::npos);
  }
  try {
    read_problem_file("/tmp");
    FAIL();
  } catch (const FileError& e) {
    EXPECT_EQ(e.message(), "is a directory, not a regular file");
  }
  try {
    read_problem_file("/dev/null");  // a device: never read (/dev/zero would never end)
    FAIL();
  } catch (const FileError& e) {
    EXPECT_EQ(e.message(), "is a character device, not a regular file");
  }
}

TEST(ProblemFile, TruthTrajectoriesNeedTruthEverywhere) {
  json d = spec_example();
  d["demonstration"][0].erase("truth");
  const Problem p = parse_problem(d.dump());
  try {
    p.truth_trajectories();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "demonstration[0].truth");
  }
}

}  // namespace
}  // namespace hbirl
