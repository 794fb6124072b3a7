// hbirl experiment: reproduce the paper's figures.
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>

#include "commands.hpp"
#include "full_commands.hpp"
#include "experiments/calibration_experiment.hpp"
#include "experiments/judged_tasks.hpp"
#include "experiments/eta_experiments.hpp"
#include "experiments/gridworld_experiment.hpp"
#include "experiments/onion_regimes.hpp"
#include "experiments/onion_experiment.hpp"
#include "experiments/random_tasks_experiment.hpp"
#include "experiments/stopping_experiment.hpp"
#include "experiments/summary.hpp"
#include "learner/input_error.hpp"
#include "learner/parallel.hpp"

namespace hbirl::cli {

namespace {

struct GridworldExperimentArgs {
  std::string out = "results";
  std::string confounders = "0,1,3,5,7,9,11,13,15";
  std::string methods = "all";
  GridworldExperimentOptions options;
};

std::vector<int> parse_int_list(const std::string& text, const std::string& field) {
  std::vector<int> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      size_t used = 0;
      const int v = std::stoi(item, &used);
      if (used != item.size() || v < 0 || v > 1000) throw std::invalid_argument(item);
      values.push_back(v);
    } catch (const std::exception&) {
      throw InputError(field, "\"" + item + "\" is not a whole number in [0, 1000]");
    }
  }
  if (values.empty()) throw InputError(field, "is empty");
  return values;
}

std::vector<GridworldMethod> parse_methods(const std::string& text) {
  if (text == "all") return all_gridworld_methods();
  std::vector<GridworldMethod> methods;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    GridworldMethod m;
    if (!parse_method(item, m)) {
      throw InputError("--methods",
                       "unknown method \"" + item +
                           "\" (true_trajectories, true_observation_function, uniform_eta, plausible_eta, ignore_ce)");
    }
    methods.push_back(m);
  }
  return methods;
}

// "\r[=======>     ] 123/2925 runs  0:42 elapsed  ETA 1:10" on stderr, at most 10 times a
// second; when stderr is not a terminal (a log file), one plain line every 10 seconds.
class ProgressBar {
 public:
  explicit ProgressBar(std::string what)
      : what_(std::move(what)), start_(std::chrono::steady_clock::now()), tty_(::isatty(STDERR_FILENO) == 1) {}
  void update(int done, int total) {
    const std::lock_guard<std::mutex> lock(mutex_);
    const auto now = std::chrono::steady_clock::now();
    if (done < total && now - last_ < std::chrono::milliseconds(tty_ ? 100 : 10000)) return;
    last_ = now;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const int width = 30;
    const int filled = total == 0 ? width : width * done / total;
    std::ostringstream line;
    if (tty_) {
      line << "\r[" << std::string(static_cast<size_t>(filled), '=') << (filled < width ? ">" : "")
           << std::string(static_cast<size_t>(std::max(0, width - filled - 1)), ' ') << "] ";
    }
    line << done << "/" << total << " " << what_ << "  " << clock(elapsed) << " elapsed";
    if (done > 0 && done < total) line << "  ETA " << clock(elapsed * (total - done) / done);
    if (done == total || !tty_) line << "\n";
    std::cerr << line.str() << std::flush;
  }

 private:
  static std::string clock(double seconds) {
    const long s = static_cast<long>(seconds + 0.5);
    std::ostringstream out;
    out << s / 60 << ":" << (s % 60 < 10 ? "0" : "") << s % 60;
    return out.str();
  }
  std::string what_;
  std::chrono::steady_clock::time_point start_;
  bool tty_;
  std::chrono::steady_clock::time_point last_{};
  std::mutex mutex_;
};

void write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw InputError("--out", "cannot write " + path.string());
}

// What every experiment writes: <stem>_runs.csv, <stem>_summary.csv and .md (mean and 95%
// CI of `values` per method and x), <stem>.png/.svg; the summary goes to stdout.
struct ExperimentOutput {
  std::string stem;
  std::string heading;   // of the markdown summary
  std::string x_name;    // CSV column
  std::string x_header;  // markdown column
  std::string footer;    // the settings, after the table
  FigureSpec figure;
};

void write_experiment(const std::string& out, const ExperimentOutput& spec, const std::string& runs_csv,
                      const std::vector<std::string>& methods, const std::vector<int>& xs,
                      const std::vector<double>& values) {
  const std::filesystem::path dir(out);
  write_file(dir / (spec.stem + "_runs.csv"), runs_csv);
  const std::vector<SummaryRow> rows = summarise(methods, xs, values);
  write_file(dir / (spec.stem + "_summary.csv"), summary_csv(rows, spec.x_name));
  std::ostringstream md;
  md << "# " << spec.heading << "\n\n" << summary_markdown(rows, spec.x_header, "ILE") << "\n" << spec.footer << "\n";
  write_file(dir / (spec.stem + "_summary.md"), md.str());
  FigureSpec figure = spec.figure;
  figure.path_stem = (dir / spec.stem).string();
  const std::string problem = draw_figure(rows, figure);
  if (!problem.empty()) std::cerr << "hbirl: warning: no figure: " << problem << "\n";
  std::cout << md.str();
  std::cerr << "hbirl: wrote " << (dir / (spec.stem + "_runs.csv")).string() << ", " << spec.stem << "_summary.csv, "
            << spec.stem << "_summary.md" << (problem.empty() ? ", " + spec.stem + ".png, " + spec.stem + ".svg" : "")
            << " in " << out << "\n";
}

void make_folder(const std::string& out) {
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) throw InputError("--out", "cannot create " + out + ": " + ec.message());
}

// The ILE of every successful run, by method label and x; failed runs are counted and
// the first few reported on stderr (`where` describes a run).
struct Collected {
  std::vector<std::string> methods;
  std::vector<int> xs;
  std::vector<double> ile;
  int failed = 0;
};

template <typename Run, typename Label, typename X, typename Where>
Collected collect(const std::vector<Run>& runs, Label label, X x, Where where) {
  Collected c;
  for (const auto& r : runs) {
    if (!r.error.empty()) {
      if (++c.failed <= 5)
        std::cerr << "hbirl: warning: run " << r.run << " (" << where(r) << ") failed: " << r.error << "\n";
      continue;
    }
    c.methods.push_back(label(r));
    c.xs.push_back(x(r));
    c.ile.push_back(r.ile);
  }
  return c;
}

std::string failed_note(int failed) {
  return failed > 0 ? "; " + std::to_string(failed) + " runs failed and are left out (see the error column)" : "";
}

// Options every experiment has.
// "posterior update" or "paper update, c = 0.5": c is the paper's step size only.
std::string update_description(AlphaUpdate update, double c) {
  std::ostringstream out;
  out << alpha_update_name(update) << " update";
  if (update == AlphaUpdate::kPaper) out << ", c = " << c;
  return out.str();
}

void add_shared_options(CLI::App* cmd, std::string& out, int& runs, AlphaUpdate& update, double& c, int& restarts,
                        std::uint64_t& seed, int& threads) {
  cmd->add_option("--out,-o", out, "Output folder")->capture_default_str();
  cmd->add_option("--runs", runs, "Runs per point")->check(CLI::Range(1, 1000000))->capture_default_str();
  add_alpha_update_option(cmd, update);
  cmd->add_option("--c", c, "The paper's step size, alpha = c alpha_dot + (1 - c) alpha (--alpha-update paper only)")
      ->check(CLI::Range(1e-6, 1.0))
      ->capture_default_str();
  cmd->add_option("--restarts", restarts, "Restarts per learning run")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--seed", seed, "Seed of every random choice")->capture_default_str();
  cmd->add_option("--threads", threads, "Threads (0 = one per core)")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
}

// Runs an experiment with a progress bar on stderr; its runs and the seconds it took.
template <typename Options, typename Runner>
auto run_with_progress(const std::string& what, Options& o, Runner runner) {
  ProgressBar bar(what);
  o.progress = [&bar](int done, int total) { bar.update(done, total); };
  const auto start = std::chrono::steady_clock::now();
  auto runs = runner(o);
  o.progress = nullptr;
  return std::make_pair(std::move(runs),
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

int run_gridworld_experiment_command(GridworldExperimentArgs& args) {
  GridworldExperimentOptions& o = args.options;
  o.confounders = parse_int_list(args.confounders, "--confounders");
  o.methods = parse_methods(args.methods);
  make_folder(args.out);
  const auto [runs, seconds] = run_with_progress("runs", o, run_gridworld_experiment);

  const Collected c = collect(
      runs, [](const GridworldRun& r) { return method_label(r.method); },
      [](const GridworldRun& r) { return r.confounders; },
      [](const GridworldRun& r) { return method_key(r.method) + ", |E| = " + std::to_string(r.confounders); });
  ExperimentOutput spec;
  spec.stem = "gridworld";
  spec.heading = "Gridworld: ILE vs number of confounding elements";
  spec.x_name = "confounders";
  spec.x_header = "|E|";
  std::ostringstream footer;
  footer << o.runs << " runs per point, " << o.trajectories << " trajectories of " << o.length << " steps, "
         << o.per_step << " observations per step, " << update_description(o.update, o.c)
         << (o.tie_actions ? ", the subject prior tied across actions" : "") << ", seed " << o.seed << "; "
         << runs.size() << " learning runs in " << static_cast<long>(seconds + 0.5) << " s on "
         << (o.threads > 0 ? o.threads : default_thread_count()) << " threads" << failed_note(c.failed) << ".";
  spec.footer = footer.str();
  spec.figure.title = "Gridworld: ILE vs confounding elements (" + std::to_string(o.runs) + " runs per point, 95% CI)";
  spec.figure.x_label = "Number of confounding elements |E|";
  spec.figure.y_label = "ILE";
  write_experiment(args.out, spec, gridworld_runs_csv(runs), c.methods, c.xs, c.ile);
  return 0;
}

// --methods of the onion experiments: "all" or a comma-separated list of keys.
std::vector<onion::OnionMethod> parse_onion_methods(const std::string& text) {
  if (text == "all") return onion::all_onion_methods();
  std::vector<onion::OnionMethod> methods;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    onion::OnionMethod m;
    if (!onion::parse_method(item, m)) {
      throw InputError("--methods",
                       "unknown method \"" + item +
                           "\" (true_trajectories, ml_trajectories, ml_observations, plausible_eta, uniform_eta)");
    }
    methods.push_back(m);
  }
  return methods;
}

struct OnionExperimentArgs {
  std::string out = "results";
  std::string trajectories = "1,2,3,4,5,6,7,8,9,10";
  std::string methods = "all";
  std::string scene = "all";
  onion::OnionExperimentOptions options;
};

int run_onion_experiment_command(OnionExperimentArgs& args) {
  onion::OnionExperimentOptions& o = args.options;
  const onion::SceneConfig elements = onion::SceneConfig::parse(args.scene, "--config");
  o.scene.blue_shirt_person = elements.blue_shirt_person;
  o.scene.other_onions = elements.other_onions;
  o.scene.foreground_person = elements.foreground_person;
  o.scene.mirror = elements.mirror;
  o.trajectories = parse_int_list(args.trajectories, "--trajectories");
  for (int n : o.trajectories) {
    if (n < 1) throw InputError("--trajectories", "needs at least 1 trajectory per point");
  }
  o.methods = parse_onion_methods(args.methods);
  make_folder(args.out);
  const auto [runs, seconds] = run_with_progress("learning runs", o, onion::run_onion_experiment);
  const Collected c = collect(
      runs, [](const onion::OnionRun& r) { return onion::method_label(r.method); },
      [](const onion::OnionRun& r) { return r.trajectories; },
      [](const onion::OnionRun& r) {
        return onion::method_key(r.method) + ", " + std::to_string(r.trajectories) + " trajectories";
      });
  ExperimentOutput spec;
  spec.stem = "onion";
  const std::string scene_note = o.scene.elements() == "all" ? "" : " (scene: " + o.scene.elements() + ")";
  spec.heading = "Onion sorting: ILE vs number of trajectories" + scene_note;
  spec.x_name = "trajectories";
  spec.x_header = "trajectories";
  std::ostringstream footer;
  footer << o.runs << " runs per point, from frames rendered at " << o.scene.width << " px, " << o.scene.fps
         << " fps, scene: " << o.scene.elements() << "; subject prior from a controlled run of " << o.controlled_sorts
         << " sorts; " << update_description(o.update, o.c) << ", seed " << o.seed << "; " << runs.size()
         << " learning runs in " << static_cast<long>(seconds + 0.5) << " s on "
         << (o.threads > 0 ? o.threads : default_thread_count()) << " threads" << failed_note(c.failed) << ".";
  spec.footer = footer.str();
  spec.figure.title =
      "Onion sorting" + scene_note + ": ILE vs trajectories (" + std::to_string(o.runs) + " runs per point, 95% CI)";
  spec.figure.x_label = "Number of trajectories";
  spec.figure.y_label = "ILE";
  write_experiment(args.out, spec, onion::onion_runs_csv(runs), c.methods, c.xs, c.ile);
  return 0;
}

// An experiment's runs back from its CSV (--summarise): `parse` names the line of anything
// wrong, and the error names the file.
template <class Run>
std::vector<Run> read_runs_csv(const std::string& path, std::vector<Run> (*parse)(const std::string&)) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("--summarise", "cannot open " + path);
  std::ostringstream text;
  text << in.rdbuf();
  try {
    return parse(text.str());
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.field(), e.message());
  }
}

struct RandomTasksArgs {
  std::string out = "results";
  std::string methods = "all";
  std::string runs_csv;  // summarise these runs instead of running
  RandomTasksOptions options;
};

int run_random_tasks_command(RandomTasksArgs& args) {
  RandomTasksOptions& o = args.options;
  o.methods = parse_random_task_methods(args.methods);
  make_folder(args.out);
  const std::filesystem::path dir(args.out);
  std::vector<RandomTaskRun> runs;
  std::ostringstream footer;
  if (!args.runs_csv.empty()) {
    runs = read_runs_csv(args.runs_csv, random_task_runs_from_csv);
    footer << runs.size() << " learning runs from " << std::filesystem::path(args.runs_csv).filename().string() << ".";
  } else {
    const auto [ran, seconds] = run_with_progress("learning runs", o, run_random_tasks);
    runs = ran;
    write_file(dir / "random_tasks_runs.csv", random_task_runs_csv(runs));
    footer << o.tasks << " tasks (seeds " << o.first_seed << "-"
           << o.first_seed + static_cast<std::uint64_t>(o.tasks) - 1 << ") x " << o.draws << " data sets each; "
           << runs.size() << " learning runs in " << static_cast<long>(seconds + 0.5) << " s on "
           << (o.threads > 0 ? o.threads : default_thread_count()) << " threads.";
  }
  // The data's sizes when fixed, as hbirl generate random-task takes them.
  std::string fixed;
  if (args.runs_csv.empty() && o.demonstrations > 0) fixed += " --demonstrations " + std::to_string(o.demonstrations);
  if (args.runs_csv.empty() && o.controlled > 0) fixed += " --controlled " + std::to_string(o.controlled);
  footer << " Reproduce one: `hbirl generate random-task --seed S --draw D" << fixed
         << " > task.json`, then `hbirl learn --problem task.json`.";
  const std::string summary = random_tasks_summary(runs, footer.str());
  write_file(dir / "random_tasks_summary.md", summary);
  const std::string problem = draw_random_tasks_figure(runs, (dir / "random_tasks").string());
  if (!problem.empty()) std::cerr << "hbirl: warning: no figure: " << problem << "\n";
  std::cout << summary;
  std::cerr << "hbirl: wrote " << (args.runs_csv.empty() ? "random_tasks_runs.csv, " : "") << "random_tasks_summary.md"
            << (problem.empty() ? ", random_tasks.png, random_tasks.svg" : "") << " in " << args.out << "\n";
  return 0;
}

// A figure's runs are the figure's own unless --first-seed says otherwise.
template <class Args>
void use_figure_seed(Args& args) {
  if (args.first_seed_given) return;
  if (const auto seed = figure_seed(args.options.tasks_from)) args.options.first_seed = *seed;
}

struct CalibrationArgs {
  std::string out = "results";
  bool first_seed_given = false;  // else a figure's runs are the figure's own (figure_seed)
  std::string data = "observations,truth";
  std::string demonstrations;  // comma-separated n, or empty: every demonstration
  std::string runs_csv;        // summarise these runs instead of running
  CalibrationOptions options;
};

std::vector<std::string> parse_calibration_data(const std::string& text) {
  std::vector<std::string> data;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    if (item != "observations" && item != "truth") {
      throw InputError("--data", "unknown data \"" + item + "\" (observations, truth)");
    }
    data.push_back(item);
  }
  if (data.empty()) throw InputError("--data", "is empty");
  return data;
}

// --demonstrations: empty for every demonstration, else each n at least 1.
std::vector<int> parse_demonstrations(const std::string& text) {
  if (text.empty()) return {};
  std::vector<int> counts = parse_int_list(text, "--demonstrations");
  for (int n : counts) {
    if (n < 1) throw InputError("--demonstrations", "each must be at least 1");
  }
  return counts;
}

int run_calibration_command(CalibrationArgs& args) {
  CalibrationOptions& o = args.options;
  use_figure_seed(args);
  o.data = parse_calibration_data(args.data);
  o.demonstrations = parse_demonstrations(args.demonstrations);
  make_folder(args.out);
  const std::filesystem::path dir(args.out);
  std::vector<CalibrationRun> runs;
  std::ostringstream footer;
  if (!args.runs_csv.empty()) {
    runs = read_runs_csv(args.runs_csv, calibration_runs_from_csv);
    footer << runs.size() << " learning runs from " << std::filesystem::path(args.runs_csv).filename().string() << ".";
  } else {
    const auto [ran, seconds] = run_with_progress("learning runs", o, run_calibration);
    runs = ran;
    write_file(dir / "calibration_runs.csv", calibration_runs_csv(runs));
    footer << judged_task_label(o.tasks_from) << ": " << o.tasks << " ("
           << judged_task_span({o.tasks_from, o.tasks, o.first_seed, o.draws}) << ")";
    if (!o.demonstrations.empty())
      footer << ", each learned from its first " << args.demonstrations << " demonstrations";
    footer << "; " << o.samples << " posterior draws, prior scale ";
    if (o.prior_scale > 0.0) {
      footer << o.prior_scale;
    } else {
      footer << "chosen by the evidence";
    }
    footer << "; " << runs.size() << " learning runs in " << static_cast<long>(seconds + 0.5) << " s on "
           << (o.threads > 0 ? o.threads : default_thread_count()) << " threads.";
  }
  if (const auto make = judged_task_problem_command(o.tasks_from)) {
    footer << " Reproduce one: `" << *make << "`, then `hbirl learn --problem task.json --posterior-samples "
           << o.samples << "` (add `--from truth` for the true steps).";
  }
  const std::string summary = calibration_summary(runs, footer.str());
  write_file(dir / "calibration_summary.md", summary);
  const std::string problem = draw_calibration_figure(runs, (dir / "calibration").string());
  if (!problem.empty()) std::cerr << "hbirl: warning: no figure: " << problem << "\n";
  std::cout << summary;
  std::cerr << "hbirl: wrote " << (args.runs_csv.empty() ? "calibration_runs.csv, " : "") << "calibration_summary.md"
            << (problem.empty() ? ", calibration.png, calibration.svg" : "") << " in " << args.out << "\n";
  return 0;
}

struct StoppingArgs {
  std::string out = "results";
  bool first_seed_given = false;
  std::string levels = "0.9,0.95";
  std::string runs_csv;  // summarise these runs instead of running
  StoppingOptions options;
};

std::vector<double> parse_levels(const std::string& text) {
  std::vector<double> levels;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    double p = 0.0;
    try {
      size_t used = 0;
      p = std::stod(item, &used);
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw InputError("--levels", "\"" + item + "\" is not a number");
    }
    if (!(p > 0.0 && p < 1.0)) throw InputError("--levels", "each must be in (0, 1)");
    levels.push_back(p);
  }
  if (levels.empty()) throw InputError("--levels", "is empty");
  return levels;
}

int run_stopping_command(StoppingArgs& args) {
  StoppingOptions& o = args.options;
  use_figure_seed(args);
  o.levels = parse_levels(args.levels);
  if (o.stop_after < 1) throw InputError("--stop-after", "must be at least 1");
  make_folder(args.out);
  const std::filesystem::path dir(args.out);
  std::vector<StoppingRun> runs;
  std::ostringstream footer;
  if (!args.runs_csv.empty()) {
    runs = read_runs_csv(args.runs_csv, stopping_runs_from_csv);
    footer << runs.size() << " tasks from " << std::filesystem::path(args.runs_csv).filename().string() << " ("
           << judged_task_label(o.tasks_from) << ", as --tasks-from says).";
  } else {
    const auto [ran, seconds] = run_with_progress("tasks", o, run_stopping);
    runs = ran;
    write_file(dir / "stopping_runs.csv", stopping_runs_csv(runs));
    footer << judged_task_label(o.tasks_from) << ": " << o.tasks << " ("
           << judged_task_span({o.tasks_from, o.tasks, o.first_seed, 1}) << ", one data set each), " << o.samples
           << " posterior draws per estimate; " << static_cast<long>(seconds + 0.5) << " s on "
           << (o.threads > 0 ? o.threads : default_thread_count()) << " threads.";
    if (const auto make = judged_task_problem_command(o.tasks_from)) {
      footer << " Reproduce one: `" << *make << "`, then `hbirl learn --problem task.json --anytime "
             << "--posterior-samples " << o.samples << "`.";
    }
  }
  const std::string summary = stopping_summary(runs, o, footer.str());
  write_file(dir / "stopping_summary.md", summary);
  const std::string problem = draw_stopping_figure(runs, o, (dir / "stopping").string());
  if (!problem.empty()) std::cerr << "hbirl: warning: no figure: " << problem << "\n";
  std::cout << summary;
  std::cerr << "hbirl: wrote " << (args.runs_csv.empty() ? "stopping_runs.csv, " : "") << "stopping_summary.md"
            << (problem.empty() ? ", stopping.png, stopping.svg" : "") << " in " << args.out << "\n";
  return 0;
}

// The Gridworld as the eta experiments watch it: --trajectories, --length, --per-step, --seed.
void add_scenario_options(CLI::App* cmd, GridworldScenarioOptions& s) {
  cmd->add_option("--trajectories", s.trajectories, "Demonstrations per run")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--length", s.length, "Steps per demonstration")->check(CLI::Range(1, 100000))->capture_default_str();
  cmd->add_option("--per-step", s.per_step, "Observations per step")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cmd->add_option("--seed", s.seed, "Seed of every random choice")->capture_default_str();
}

std::string run_footer(const std::string& what, size_t runs, int per_cell, const GridworldScenarioOptions& s,
                       double seconds, int threads) {
  std::ostringstream footer;
  footer << per_cell << " runs per cell, " << s.trajectories << " demonstrations of " << s.length << " steps, "
         << s.per_step << " observations per step, posterior update, seed " << s.seed << "; " << runs << " " << what
         << " in " << static_cast<long>(seconds + 0.5) << " s on " << (threads > 0 ? threads : default_thread_count())
         << " threads.";
  return footer.str();
}

struct EtaSensitivityArgs {
  std::string out = "results";
  std::string confounders = "3,7";
  std::string masses = "0.4,0.6,0.8,0.95";
  std::string accuracies = "0.2,0.4,0.6,0.8,1.0";
  EtaSensitivityOptions options;
};

// Comma-separated numbers in [lo, hi].
std::vector<double> parse_numbers(const std::string& text, const char* option, double lo, double hi) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      size_t used = 0;
      const double x = std::stod(item, &used);
      if (used != item.size() || !(x >= lo && x <= hi)) throw std::invalid_argument(item);
      out.push_back(x);
    } catch (const std::exception&) {
      std::ostringstream range;
      range << "[" << lo << ", " << hi << "]";
      throw InputError(option, "expected comma-separated numbers in " + range.str() + ", got \"" + item + "\"");
    }
  }
  if (out.empty()) throw InputError(option, "is empty");
  return out;
}

int run_eta_sensitivity_command(EtaSensitivityArgs& args) {
  EtaSensitivityOptions& o = args.options;
  o.confounders = parse_int_list(args.confounders, "--confounders");
  for (int e : o.confounders) {
    if (e < 1)
      throw InputError("--confounders", "needs at least one element per entry (a labeller picks between sources)");
  }
  o.masses = parse_numbers(args.masses, "--masses", 0.01, 1.0);
  o.accuracies = parse_numbers(args.accuracies, "--accuracies", 0.0, 1.0);
  make_folder(args.out);
  const std::filesystem::path dir(args.out);
  const auto [runs, seconds] = run_with_progress("learning runs", o, run_eta_sensitivity);
  write_file(dir / "eta_sensitivity_runs.csv", eta_runs_csv(runs));
  const std::string summary = eta_sensitivity_summary(
      runs, run_footer("learning runs", runs.size(), o.runs, o.scenario, seconds, o.threads) + " eta_prior_strength " +
                std::to_string(o.eta_prior_strength).substr(0, 4) + ".");
  write_file(dir / "eta_sensitivity_summary.md", summary);
  const std::string problem = draw_eta_sensitivity_figure(runs, (dir / "eta_sensitivity").string());
  if (!problem.empty()) std::cerr << "hbirl: warning: no figure: " << problem << "\n";
  std::cout << summary;
  std::cerr << "hbirl: wrote eta_sensitivity_runs.csv, eta_sensitivity_summary.md"
            << (problem.empty() ? ", eta_sensitivity.png, eta_sensitivity.svg" : "") << " in " << args.out << "\n";
  return 0;
}

struct UnlistedArgs {
  std::string out = "results";
  std::string confounders = "0,1,3,5,7";
  std::string told = "0,1";
  UnlistedOptions options;
};

int run_unlisted_command(UnlistedArgs& args) {
  UnlistedOptions& o = args.options;
  o.confounders = parse_int_list(args.confounders, "--confounders");
  o.told = parse_int_list(args.told, "--told");
  make_folder(args.out);
  const std::filesystem::path dir(args.out);
  const auto [runs, seconds] = run_with_progress("learning runs", o, run_unlisted);
  write_file(dir / "unlisted_runs.csv", unlisted_runs_csv(runs));
  std::ostringstream eps;
  eps << " The catch-all's share of eta: " << o.unlisted_eta << ".";
  const std::string summary = unlisted_summary(
      runs, run_footer("learning runs", runs.size(), o.runs, o.scenario, seconds, o.threads) + eps.str());
  write_file(dir / "unlisted_summary.md", summary);
  const std::string problem = draw_unlisted_figure(runs, (dir / "unlisted").string());
  if (!problem.empty()) std::cerr << "hbirl: warning: no figure: " << problem << "\n";
  std::cout << summary;
  std::cerr << "hbirl: wrote unlisted_runs.csv, unlisted_summary.md"
            << (problem.empty() ? ", unlisted.png, unlisted.svg" : "") << " in " << args.out << "\n";
  return 0;
}

struct OnionRegimesArgs {
  std::string out = "results";
  std::string shares = "0,0.25,0.5,0.75,0.9";
  std::string eta_powers = "1,3";
  std::string methods = "all";
  int trajectories = 6;
  onion::OnionRegimesOptions options;
};

int run_onion_regimes_command(OnionRegimesArgs& args) {
  onion::OnionRegimesOptions& o = args.options;
  o.shares = parse_numbers(args.shares, "--shares", 0.0, 0.95);
  o.eta_powers = parse_numbers(args.eta_powers, "--eta-powers", 0.05, 20.0);
  o.base.trajectories = {args.trajectories};
  o.base.methods = parse_onion_methods(args.methods);
  make_folder(args.out);
  const std::filesystem::path dir(args.out);
  const auto [runs, seconds] = run_with_progress("learning runs", o, onion::run_onion_regimes);
  write_file(dir / "onion_regimes_runs.csv", onion::onion_regimes_csv(runs));
  std::ostringstream footer;
  footer << o.base.runs << " runs per point, " << args.trajectories << " sorts each, frames rendered at "
         << o.base.scene.width << " px, " << o.base.scene.fps
         << " fps, with the blue-shirt person and the other onions; subject prior from a controlled run of "
         << o.base.controlled_sorts << " sorts; posterior update (eta learned per context by Plausible eta), seed "
         << o.base.seed << "; " << runs.size() << " learning runs in " << static_cast<long>(seconds + 0.5) << " s on "
         << (o.base.threads > 0 ? o.base.threads : default_thread_count()) << " threads.";
  const std::string summary = onion::onion_regimes_summary(runs, footer.str());
  write_file(dir / "onion_regimes_summary.md", summary);
  const std::string problem = onion::draw_onion_regimes_figure(runs, (dir / "onion_regimes").string());
  if (!problem.empty()) std::cerr << "hbirl: warning: no figure: " << problem << "\n";
  std::cout << summary;
  std::cerr << "hbirl: wrote onion_regimes_runs.csv, onion_regimes_summary.md"
            << (problem.empty() ? ", onion_regimes.png, onion_regimes.svg" : "") << " in " << args.out << "\n";
  return 0;
}

// experiment gridworld: the paper's Gridworld figure.
CLI::App* add_gridworld_experiment(CLI::App* cmd, GridworldExperimentArgs& args) {
  CLI::App* grid =
      cmd->add_subcommand("gridworld",
                          "The paper's Gridworld figure: ILE of five methods (True Trajectories, True Observation\n"
                          "Function, Uniform eta, Plausible eta, Ignore CE) vs the number of confounding\n"
                          "elements. Writes gridworld_runs.csv (one row per run), gridworld_summary.csv and .md\n"
                          "(mean and 95% CI) and gridworld.png/.svg (needs gnuplot) to --out, and prints the\n"
                          "summary. Runs in parallel; the numbers do not depend on --threads.");
  add_shared_options(grid, args.out, args.options.runs, args.options.update, args.options.c, args.options.restarts,
                     args.options.seed, args.options.threads);
  grid->add_option("--confounders", args.confounders, "Numbers of confounding elements, comma-separated")
      ->capture_default_str();
  grid->add_option("--methods", args.methods,
                   "Comma-separated: true_trajectories, true_observation_function, uniform_eta, plausible_eta, "
                   "ignore_ce; or all")
      ->capture_default_str();
  grid->add_option("--trajectories", args.options.trajectories, "Trajectories per run")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  grid->add_option("--length", args.options.length, "Steps per trajectory")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  grid->add_option("--per-step", args.options.per_step, "Observations per step")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  grid->add_option("--max-alpha-iterations", args.options.max_alpha_iterations,
                   "Observation-model refinements per E-step")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  grid->add_option("--alpha-tolerance", args.options.alpha_tolerance,
                   "The observation model has converged below this change")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  grid->add_option("--theta-tolerance", args.options.theta_tolerance,
                   "EM stops when theta moves less than this (relative)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  grid->add_option("--likelihood-tolerance", args.options.likelihood_tolerance,
                   "EM stops when the log-likelihood moves less than this (relative)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  grid->add_flag("!--plain-em", args.options.accelerate, "Plain EM iterations instead of SQUAREM-accelerated EM");
  grid->add_flag("--tie-actions", args.options.tie_actions,
                 "Tie the subject's prior across each state's actions (observation_model.tie_actions; docs/MODEL.md)");
  return grid;
}

// experiment onion: the paper's onion-sorting figure.
CLI::App* add_onion_experiment(CLI::App* cmd, OnionExperimentArgs& args) {
  CLI::App* onion_cmd =
      cmd->add_subcommand("onion",
                          "The paper's onion-sorting figure, from rendered frames: ILE of five methods (True\n"
                          "Trajectories, ML Trajectories, ML Observations, Plausible eta, Uniform eta) vs the\n"
                          "number of demonstrated sorts, in a scene with three confounding elements and a\n"
                          "mirror. Writes onion_runs.csv, onion_summary.csv and .md and onion.png/.svg to --out\n"
                          "and prints the summary. Runs in parallel; the numbers do not depend on --threads.");
  add_shared_options(onion_cmd, args.out, args.options.runs, args.options.update, args.options.c, args.options.restarts,
                     args.options.seed, args.options.threads);
  onion_cmd->add_option("--trajectories", args.trajectories, "Numbers of trajectories (sorts), comma-separated")
      ->capture_default_str();
  onion_cmd
      ->add_option(
          "--methods", args.methods,
          "Comma-separated: true_trajectories, ml_trajectories, ml_observations, plausible_eta, uniform_eta; or all")
      ->capture_default_str();
  onion_cmd
      ->add_option("--controlled-sorts", args.options.controlled_sorts,
                   "Sorts in the controlled run that gives the subject prior")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  onion_cmd
      ->add_option("--config,-c", args.scene,
                   "Demonstrations' scene: all (three confounding elements and the mirror), controlled, or a "
                   "comma-separated list of blue-shirt, other-onions, foreground, mirror")
      ->capture_default_str();
  onion_cmd->add_option("--width", args.options.scene.width, "Frame width in pixels")
      ->check(CLI::Range(onion::camera_view().min_width, onion::camera_view().max_width))
      ->capture_default_str();
  onion_cmd->add_option("--fps", args.options.scene.fps, "Frames per simulated second")
      ->check(CLI::Range(1, 240))
      ->capture_default_str();
  return onion_cmd;
}

// The random-task experiment's method keys, comma-separated (all_random_task_methods).
std::string random_task_method_keys() {
  std::string keys;
  for (const RandomTaskMethod& m : all_random_task_methods()) keys += (keys.empty() ? "" : ", ") + m.key;
  return keys;
}

// experiment random-tasks: hbirl on random tasks.
CLI::App* add_random_tasks_experiment(CLI::App* cmd, RandomTasksArgs& args) {
  CLI::App* tasks_cmd = cmd->add_subcommand(
      "random-tasks",
      "hbirl on random tasks nobody tuned it for (hbirl generate random-task): each task learned from its\n"
      "true trajectories, with O fixed at the controlled run's prior, with the paper's update (c = 0.5, 0.1) and\n"
      "with the default posterior update (c = 0.1, and 0.5, 0.02; 4 restarts); and the information limit's oracles\n"
      "(the true O's and each eta read as the simulator's rules say, nothing learned; also told which terminal\n"
      "state each trajectory entered; the true O's, or the subject's (all of it, or where the controlled run saw\n"
      "it, or where it never saw it) or the elements' alone, with the rest learned; the default with the prior\n"
      "strength fixed at 1, 1000, started at the oracle's O's and eta, with a base pseudo-count of 0.1 or 0.3,\n"
      "with the pairs the controlled run never saw learned, with a cross-fitted E-step, and with the elements'\n"
      "flat prior 0.1-1000 times as strong, and with the subject's prior tied across a state's actions; the\n"
      "labelled oracles: O from the data with every hidden step and source revealed, each trajectory's own\n"
      "included or left out, held or as the prior of its own O),\n"
      "the default with a sensor that sees which, and the default and the oracle with the task's noisy end\n"
      "sensor (1-3 reports of the terminal state entered). Writes random_tasks_runs.csv (one row\n"
      "per run), random_tasks_summary.md (share of runs with an optimal learned policy and relative ILE per\n"
      "method, by confounders, occlusion, sensor informativeness and eta; paired comparisons; dependence on c;\n"
      "restarts) and random_tasks.png/.svg to --out. The numbers do not depend on --threads.");
  tasks_cmd->add_option("--out,-o", args.out, "Output folder")->capture_default_str();
  tasks_cmd->add_option("--tasks", args.options.tasks, "Number of tasks")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  tasks_cmd->add_option("--draws", args.options.draws, "Data sets per task")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  tasks_cmd->add_option("--first-seed", args.options.first_seed, "Seed of the first task")->capture_default_str();
  tasks_cmd
      ->add_option("--controlled", args.options.controlled,
                   "Trajectories of every task's controlled run (default: as each task draws it, 5-30): how "
                   "much of the learner's gap to the oracles is the subject prior's information")
      ->check(CLI::Range(1, 100000));
  tasks_cmd
      ->add_option("--demonstrations", args.options.demonstrations,
                   "Demonstrations of every data set (default: as each draws it, 5-40): does the learner's gap to "
                   "the oracles close as it sees more of the expert?")
      ->check(CLI::Range(1, 100000));
  tasks_cmd->add_option("--methods", args.methods, "Comma-separated: " + random_task_method_keys() + "; or all")
      ->capture_default_str();
  tasks_cmd->add_option("--threads", args.options.threads, "Threads (0 = one per core)")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  tasks_cmd->add_option("--summarise", args.runs_csv,
                        "Do not run: summarise and draw the runs of this random_tasks_runs.csv into --out");
  return tasks_cmd;
}

// --tasks-from of the experiments that judge the confidence (judged_tasks.hpp).
void add_tasks_from(CLI::App* c, std::string& tasks_from) {
  c->add_option("--tasks-from", tasks_from,
                "random (random tasks, --draws data sets each where there is --draws); gridworld (the Gridworld\n"
                "figure's runs: task t with |E| = 0, 1, 3, ..., 15 in turn, plausible eta, 20 demonstrations); onion\n"
                "(the onion figure's runs: 10 sorts rendered and perceived, the labeller's eta). For a figure,\n"
                "--first-seed is the figure's seed and task t its run t")
      ->check(CLI::IsMember(judged_task_sources()))
      ->capture_default_str();
}

// What the experiments that judge the confidence share (judged_tasks.hpp): where the
// tasks come from, how many, from which seed, on how many threads, written where.
template <class Args>
void add_judged_task_options(CLI::App* c, Args& args) {
  c->add_option("--out,-o", args.out, "Output folder")->capture_default_str();
  c->add_option("--tasks", args.options.tasks, "Number of tasks")->check(CLI::Range(1, 1000000))->capture_default_str();
  c->add_option("--first-seed", args.options.first_seed,
                "Seed of the first task (with --tasks-from gridworld or onion: the figure's seed, by default its own)")
      ->each([&args](const std::string&) { args.first_seed_given = true; })
      ->capture_default_str();
  add_tasks_from(c, args.options.tasks_from);
  c->add_option("--threads", args.options.threads, "Threads (0 = one per core)")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
}

// experiment calibration: is the posterior's confidence a promise?
CLI::App* add_calibration_experiment(CLI::App* cmd, CalibrationArgs& args) {
  CLI::App* c = cmd->add_subcommand(
      "calibration",
      "Is the confidence calibrated? Random tasks (seeds from --first-seed: not those the posterior's defaults\n"
      "were looked at on) or a figure's runs (--tasks-from), each data set learned as hbirl learn\n"
      "--posterior-samples learns it, from the observations and from the true trajectories; the confidence (the\n"
      "posterior probability that the learned policy is within 5% of the optimal value) against whether it is.\n"
      "Writes calibration_runs.csv, calibration_summary.md (AUROC, expected calibration error, Brier score, share\n"
      "right among confidence >= 0.9, the reliability table) and calibration.png/.svg (the reliability diagram) to\n"
      "--out. The numbers do not depend on --threads.");
  add_judged_task_options(c, args);
  c->add_option("--draws", args.options.draws, "Data sets per task")->check(CLI::Range(1, 1000))->capture_default_str();
  c->add_option("--samples", args.options.samples, "Posterior draws per run (--posterior-samples)")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  c->add_option("--prior-scale", args.options.prior_scale,
                "The prior's scale sigma (--prior-scale); 0: chosen by the evidence, as hbirl learn does")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  c->add_option("--data", args.data, "Comma-separated: observations, truth")->capture_default_str();
  c->add_option("--demonstrations", args.demonstrations,
                "Comma-separated n: learn each data set from its first n demonstrations, a run per n (e.g. 1,2,3\n"
                "for the onion figure's first points); default: from every demonstration");
  c->add_option("--summarise", args.runs_csv,
                "Do not run: summarise and draw the runs of this calibration_runs.csv into --out");
  return c;
}

// experiment stopping: knowing when it has seen enough.
CLI::App* add_stopping_experiment(CLI::App* cmd, StoppingArgs& args) {
  CLI::App* c = cmd->add_subcommand(
      "stopping",
      "Knowing when it has seen enough: random tasks (or a figure's runs, --tasks-from) learned while their\n"
      "demonstrations arrive (hbirl learn --anytime --posterior-samples), then the stop rule (--stop-after\n"
      "estimates in a row with confidence >= p) for each level p: after how many demonstrations it stops and how\n"
      "often the policy it stops with is right, against every demonstration. Writes stopping_runs.csv (one row per "
      "estimate), stopping_summary.md and\n"
      "stopping.png/.svg to --out. The numbers do not depend on --threads.");
  add_judged_task_options(c, args);
  c->add_option("--samples", args.options.samples, "Posterior draws per estimate")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  c->add_option("--levels", args.levels, "Confidence levels p, comma-separated, each in (0, 1)")->capture_default_str();
  c->add_option("--stop-after", args.options.stop_after, "Estimates in a row at or above p")->capture_default_str();
  c->add_option("--summarise", args.runs_csv,
                "Do not run: summarise and draw the runs of this stopping_runs.csv into --out (with its --tasks-from\n"
                "and --samples for the labels)");
  return c;
}

// experiment eta-sensitivity: learned vs stated eta under imperfect labellers.
CLI::App* add_eta_sensitivity_experiment(CLI::App* cmd, EtaSensitivityArgs& args) {
  CLI::App* eta_cmd = cmd->add_subcommand(
      "eta-sensitivity",
      "Beyond the paper: the Gridworld watched by a labeller that gives its pick --masses of eta and picks the true\n"
      "source with probability --accuracies; ILE with eta as stated and with eta learned per context (the labeller's\n"
      "pick), against a perfect labeller. Writes eta_sensitivity_runs.csv, eta_sensitivity_summary.md (heat-map\n"
      "tables, paired comparisons, how much of the gap to the perfect labeller learned eta closes, learned vs true\n"
      "calibration) and eta_sensitivity.png/.svg to --out. The numbers do not depend on --threads.");
  eta_cmd->add_option("--out,-o", args.out, "Output folder")->capture_default_str();
  eta_cmd->add_option("--runs", args.options.runs, "Runs per cell")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  eta_cmd->add_option("--confounders", args.confounders, "Numbers of confounding elements, comma-separated")
      ->capture_default_str();
  eta_cmd->add_option("--masses", args.masses, "The labeller's share of eta for its pick, comma-separated")
      ->capture_default_str();
  eta_cmd->add_option("--accuracies", args.accuracies, "How often its pick is the true source, comma-separated")
      ->capture_default_str();
  eta_cmd
      ->add_option("--eta-prior-strength", args.options.eta_prior_strength,
                   "kappa of learned eta (observation_model.eta_prior_strength)")
      ->check(CLI::Range(1e-6, 1e12))
      ->capture_default_str();
  add_scenario_options(eta_cmd, args.options.scenario);
  eta_cmd->add_option("--threads", args.options.threads, "Threads (0 = one per core)")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  return eta_cmd;
}

// experiment unlisted: confounding elements the learner is not told of.
CLI::App* add_unlisted_experiment(CLI::App* cmd, UnlistedArgs& args) {
  CLI::App* unlisted_cmd = cmd->add_subcommand(
      "unlisted",
      "Beyond the paper: the Gridworld with --confounders true elements of which the learner is told --told (0: eta "
      "over\n"
      "the subject alone). Methods: as told, with the catch-all unlisted source (eta fixed, eta learned), and the\n"
      "oracle told every element. Writes unlisted_runs.csv, unlisted_summary.md (ILE and subject-or-not label\n"
      "accuracy per |E|) and unlisted.png/.svg to --out. The numbers do not depend on --threads.");
  unlisted_cmd->add_option("--out,-o", args.out, "Output folder")->capture_default_str();
  unlisted_cmd->add_option("--runs", args.options.runs, "Runs per point")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  unlisted_cmd->add_option("--confounders", args.confounders, "True numbers of elements, comma-separated")
      ->capture_default_str();
  unlisted_cmd->add_option("--told", args.told, "How many of them the learner is told, comma-separated")
      ->capture_default_str();
  unlisted_cmd
      ->add_option("--unlisted-eta", args.options.unlisted_eta,
                   "The catch-all's share of every eta (observation_model.unlisted_source.eta)")
      ->check(CLI::Range(1e-6, 1.0 - 1e-6))
      ->capture_default_str();
  add_scenario_options(unlisted_cmd, args.options.scenario);
  unlisted_cmd->add_option("--threads", args.options.threads, "Threads (0 = one per core)")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  return unlisted_cmd;
}

// experiment onion-regimes: where each onion baseline breaks.
CLI::App* add_onion_regimes_experiment(CLI::App* cmd, OnionRegimesArgs& args) {
  args.options.base.runs = 20;
  CLI::App* regimes_cmd = cmd->add_subcommand(
      "onion-regimes",
      "Beyond the paper: where each onion baseline breaks. ILE of the five methods at --trajectories sorts as the\n"
      "foreground person's share of the time in front of the expert goes through --shares (0: absent), with and\n"
      "without the mirror, and with the labeller's eta as stated or overconfident (--eta-powers: eta raised to the\n"
      "power and renormalised). Writes onion_regimes_runs.csv, onion_regimes_summary.md and onion_regimes.png/.svg\n"
      "to --out. The numbers do not depend on --threads.");
  add_shared_options(regimes_cmd, args.out, args.options.base.runs, args.options.base.update, args.options.base.c,
                     args.options.base.restarts, args.options.base.seed, args.options.base.threads);
  regimes_cmd
      ->add_option("--shares", args.shares,
                   "Foreground person's shares of the time in front, comma-separated, in [0, 0.95]")
      ->capture_default_str();
  regimes_cmd
      ->add_option("--eta-powers", args.eta_powers, "The labeller's eta raised to each of these powers (1: as stated)")
      ->capture_default_str();
  regimes_cmd->add_option("--trajectories", args.trajectories, "Sorts learned from")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  regimes_cmd
      ->add_option("--controlled-sorts", args.options.base.controlled_sorts,
                   "Sorts in the controlled run that gives the subject prior")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  regimes_cmd
      ->add_option(
          "--methods", args.methods,
          "Comma-separated: true_trajectories, ml_trajectories, ml_observations, plausible_eta, uniform_eta; or all")
      ->capture_default_str();
  return regimes_cmd;
}

// A subcommand declared by `declare` on `cmd` (in the order of the calls: --help's), and
// the command `run` is with its arguments.
struct Subcommand {
  CLI::App* app;
  Command run;
};

template <typename Args>
Subcommand subcommand(CLI::App* cmd, CLI::App* (*declare)(CLI::App*, Args&), int (*run)(Args&)) {
  auto args = std::make_shared<Args>();
  CLI::App* app = declare(cmd, *args);
  return {app, [args, run] { return run(*args); }};
}

}  // namespace

Command add_experiment(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(kExperiment.name, kExperiment.description);
  cmd->require_subcommand(1);  // exactly one: the one parsed is run
  const std::vector<Subcommand> experiments = {
      subcommand(cmd, add_gridworld_experiment, run_gridworld_experiment_command),
      subcommand(cmd, add_onion_experiment, run_onion_experiment_command),
      subcommand(cmd, add_random_tasks_experiment, run_random_tasks_command),
      subcommand(cmd, add_calibration_experiment, run_calibration_command),
      subcommand(cmd, add_stopping_experiment, run_stopping_command),
      subcommand(cmd, add_eta_sensitivity_experiment, run_eta_sensitivity_command),
      subcommand(cmd, add_unlisted_experiment, run_unlisted_command),
      subcommand(cmd, add_onion_regimes_experiment, run_onion_regimes_command)};
  return [experiments] {
    for (const Subcommand& e : experiments) {
      if (e.app->parsed()) return e.run();
    }
    return 2;
  };
}

}  // namespace hbirl::cli
