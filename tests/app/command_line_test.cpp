#include "app/command_line.hpp"

#include <gtest/gtest.h>

#include <set>

namespace hbirl::app {
namespace {

std::set<std::string> flags_of(const CLI::App& app) {
  std::set<std::string> out;
  for (const CLI::Option* o : app.get_options()) {
    for (const std::string& name : o->get_lnames()) out.insert("--" + name);
  }
  return out;
}

// The options are the schema's: every setting on the command line, those the optimiser can
// use on it, the engine's on hbirl posterior; a word reaches the settings.
TEST(CommandLine, OptionsAreTheSchemas) {
  LearnSettings all, optimiser, engine;
  CLI::App a, o, e;
  add_learn_settings(&a, all, Front::kCommandLine);
  add_learn_settings(&o, optimiser, Front::kOptimiser);
  add_learn_settings(&e, engine, Front::kEngine);
  const std::set<std::string> on_a = flags_of(a), on_o = flags_of(o), on_e = flags_of(e);
  for (const Setting& s : learn_settings_schema()) {
    EXPECT_TRUE(on_a.count(s.flag)) << s.flag;
    EXPECT_EQ(on_o.count(s.flag), s.optimiser ? 1u : 0u) << s.flag;
    EXPECT_EQ(on_e.count(s.flag), s.group == Setting::Group::kEngine ? 1u : 0u) << s.flag;
  }
  EXPECT_FALSE(on_o.count("--engine"));
  a.parse("--max-em-iterations 7 --eta stated --seed 9 --learn-observation-model false", false);
  EXPECT_EQ(all.em.max_em_iterations, 7);
  EXPECT_EQ(all.learn_eta, false);
  EXPECT_EQ(all.em.seed, 9u);
  EXPECT_EQ(all.learn_observation_model, false);
  EXPECT_EQ(all.alpha_update, std::nullopt);  // not given: as the prior says
}

TEST(CommandLine, AWordOutOfRangeIsAParseErrorNamingTheOption) {
  LearnSettings settings;
  CLI::App app;
  add_learn_settings(&app, settings, Front::kCommandLine);
  try {
    app.parse("--restarts 0", false);
    FAIL() << "--restarts 0 accepted";
  } catch (const CLI::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("--restarts"), std::string::npos) << e.what();
  }
  EXPECT_THROW(app.parse("--alpha-update sometimes", false), CLI::ParseError);
  EXPECT_EQ(settings.em.restarts, 1);
}

}  // namespace
}  // namespace hbirl::app
