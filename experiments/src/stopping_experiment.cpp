#include "experiments/stopping_experiment.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "app/learn.hpp"
#include "experiments/judged_tasks.hpp"
#include "experiments/summary.hpp"
#include "learner/input_error.hpp"
#include "learner/metrics.hpp"

namespace hbirl {

namespace {

// The task learned while its demonstrations arrive, as hbirl learn --anytime
// --posterior-samples does, one thread: the confidence and ILE after each.
void learn_while_watching(const JudgedTask& task, const StoppingOptions& o, StoppingRun& r) {
  app::LearnSettings settings;
  settings.em.threads = 1;
  settings.em.seed = r.seed * 1000003ull + static_cast<std::uint64_t>(r.draw);
  settings.posterior.samples = o.samples;
  app::learn_anytime(task.mdp, task.observed, task.prior, settings, {}, [&](int, const app::Learned& learned) {
    r.confidence.push_back(learned.confidence->near_optimal);
    r.ile_relative.push_back(inverse_learning_error(task.mdp, task.true_weights, learned.em.theta).relative());
  });
}

// Where the rule at level p stops a run: the number of demonstrations (0: never).
int stop_point(const StoppingRun& r, double p, int after) {
  app::StopRule rule(p, after);
  for (size_t n = 0; n < r.confidence.size(); ++n) {
    if (rule.holds_with(r.confidence[n])) return static_cast<int>(n) + 1;
  }
  return 0;
}

bool right_at(const StoppingRun& r, int n) { return r.ile_relative[static_cast<size_t>(n) - 1] <= kNearOptimalShare; }

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

std::vector<const StoppingRun*> usable(const std::vector<StoppingRun>& runs) {
  std::vector<const StoppingRun*> out;
  for (const StoppingRun& r : runs) {
    if (r.error.empty() && !r.confidence.empty()) out.push_back(&r);
  }
  return out;
}

}  // namespace

std::vector<StoppingRun> run_stopping(const StoppingOptions& o) {
  return on_judged_tasks<StoppingRun>(
      {o.tasks_from, o.tasks, o.first_seed, 1}, 1, o.threads, o.progress,
      [&](const JudgedTask& task, size_t, StoppingRun& run) { learn_while_watching(task, o, run); });
}

std::string stopping_runs_csv(const std::vector<StoppingRun>& runs) {
  std::ostringstream out;
  out.precision(10);
  out << "seed,draw,demonstrations,confidence,ile_relative,right,error\n";
  for (const StoppingRun& r : runs) {
    if (!r.error.empty()) out << r.seed << "," << r.draw << ",,,,," << csv_text(r.error) << "\n";
    for (size_t n = 0; n < r.confidence.size(); ++n) {
      out << r.seed << "," << r.draw << "," << n + 1 << "," << r.confidence[n] << "," << r.ile_relative[n] << ","
          << (r.ile_relative[n] <= kNearOptimalShare ? 1 : 0) << ",\n";
    }
  }
  return out.str();
}

std::vector<StoppingRun> stopping_runs_from_csv(const std::string& csv) {
  std::istringstream in(csv);
  std::string line;
  if (!std::getline(in, line) || line + "\n" != stopping_runs_csv({})) {
    throw InputError("runs CSV", "line 1: not a stopping_runs.csv header");
  }
  std::vector<StoppingRun> runs;
  for (int number = 2; std::getline(in, line); ++number) {
    const std::vector<std::string> f = csv_cells(line);
    const std::string where = "line " + std::to_string(number) + ": ";
    if (f.size() != 7) throw InputError("runs CSV", where + std::to_string(f.size()) + " fields, expected 7");
    try {
      const std::uint64_t seed = std::stoull(f[0]);
      const int draw = std::stoi(f[1]);
      if (runs.empty() || runs.back().seed != seed || runs.back().draw != draw) {
        runs.emplace_back();
        runs.back().seed = seed;
        runs.back().draw = draw;
      }
      StoppingRun& r = runs.back();
      if (f[2].empty()) {  // a task that failed
        r.error = f[6];
        continue;
      }
      if (std::stoi(f[2]) != static_cast<int>(r.confidence.size()) + 1) {
        throw InputError("runs CSV", where + "the estimates of a task must come in order 1, 2, ...");
      }
      r.confidence.push_back(std::stod(f[3]));
      r.ile_relative.push_back(std::stod(f[4]));
    } catch (const std::logic_error&) {
      throw InputError("runs CSV", where + "a field is not a number");
    }
  }
  return runs;
}

std::string stopping_summary(const std::vector<StoppingRun>& runs, const StoppingOptions& o,
                             const std::string& footer) {
  const std::vector<const StoppingRun*> ok = usable(runs);
  int right_at_end = 0;
  for (const StoppingRun* r : ok) right_at_end += right_at(*r, static_cast<int>(r->confidence.size())) ? 1 : 0;
  std::ostringstream out;
  out << "# Knowing when it has seen enough\n\n"
      << judged_task_label(o.tasks_from)
      << ", learned from their observations while the demonstrations arrive (`hbirl learn --anytime "
         "--posterior-samples "
      << o.samples << "`); the rule stops once " << o.stop_after
      << " estimates in a row have a confidence >= p. Right: the policy within 5% of the optimal value.\n\n"
      << "| p | tasks stopped | demonstrations at the stop: median [quartiles] | share of the task's used (median) "
         "| right when stopped | the same tasks, right with every demonstration | not stopped: right at the end |\n"
      << "|---|---|---|---|---|---|---|\n";
  for (double p : o.levels) {
    std::vector<double> at, share;
    int right_stopped = 0, right_all = 0, not_stopped = 0, right_not_stopped = 0;
    for (const StoppingRun* r : ok) {
      const int n = stop_point(*r, p, o.stop_after);
      const int all = static_cast<int>(r->confidence.size());
      if (n == 0) {
        ++not_stopped;
        right_not_stopped += right_at(*r, all) ? 1 : 0;
        continue;
      }
      at.push_back(n);
      share.push_back(static_cast<double>(n) / all);
      right_stopped += right_at(*r, n) ? 1 : 0;
      right_all += right_at(*r, all) ? 1 : 0;
    }
    const int stopped = static_cast<int>(at.size());
    const auto [lo, hi] = wilson(right_stopped, stopped);
    char row[400];
    std::snprintf(
        row, sizeof row,
        "| %.2f | %d of %zu | %.0f [%.0f, %.0f] | %.0f%% | %d of %d (%.1f%% [%.1f, %.1f]) | %d of %d | %d of %d "
        "|\n",
        p, stopped, ok.size(), quantile(at, 0.5), quantile(at, 0.25), quantile(at, 0.75), 100.0 * quantile(share, 0.5),
        right_stopped, stopped, stopped ? 100.0 * right_stopped / stopped : 0.0, 100.0 * lo, 100.0 * hi, right_all,
        stopped, right_not_stopped, not_stopped);
    out << row;
  }
  out << "\nWith every demonstration, " << right_at_end << " of " << ok.size() << " tasks are right.";
  const long failed = std::count_if(runs.begin(), runs.end(), [](const StoppingRun& r) { return !r.error.empty(); });
  if (failed > 0) out << " " << failed << " tasks failed (their error is in stopping_runs.csv).";
  out << "\n\n" << footer << "\n";
  return out.str();
}

std::string draw_stopping_figure(const std::vector<StoppingRun>& runs, const StoppingOptions& o,
                                 const std::string& path_stem) {
  const std::vector<const StoppingRun*> ok = usable(runs);
  if (ok.empty()) return "no runs";
  size_t longest = 0;
  for (const StoppingRun* r : ok) longest = std::max(longest, r->confidence.size());
  // Per n: the share right and the mean confidence among tasks with at least n
  // demonstrations (where at least 5 tasks, or all, have that many).
  std::ostringstream data;
  data << "$curve << EOD\n";
  for (size_t n = 1; n <= longest; ++n) {
    int tasks = 0, right = 0;
    double confidence = 0.0;
    for (const StoppingRun* r : ok) {
      if (r->confidence.size() < n) continue;
      ++tasks;
      right += r->ile_relative[n - 1] <= kNearOptimalShare ? 1 : 0;
      confidence += r->confidence[n - 1];
    }
    if (tasks >= std::min<int>(5, static_cast<int>(ok.size())))
      data << n << " " << static_cast<double>(right) / tasks << " " << confidence / tasks << "\n";
  }
  data << "EOD\n";
  for (size_t l = 0; l < o.levels.size(); ++l) {
    data << "$stop" << l << " << EOD\n";
    for (const StoppingRun* r : ok) {
      const int n = stop_point(*r, o.levels[l], o.stop_after);
      if (n > 0) data << n << " " << (right_at(*r, n) ? 1 : 0) << "\n";
    }
    data << "EOD\n";
  }
  std::ostringstream plot;
  plot << "set multiplot layout 2,1\nset grid\nset key bottom right\nset xlabel 'demonstrations seen'\n"
       << "set yrange [0:1.05]\nset title "
       << gnuplot_quoted(judged_task_label(o.tasks_from) + " while watched: share right and mean confidence") << "\n"
       << "plot $curve using 1:2 with linespoints lw 2 pt 7 lc rgb '#1b9e77' title 'share right (tasks with >= n "
          "demonstrations)', "
       << "$curve using 1:3 with linespoints lw 2 pt 5 lc rgb '#7570b3' title 'mean confidence'\n"
       << "set title 'Where the rule stopped (" << o.stop_after
       << " in a row): demonstrations at the stop'\nset ylabel 'tasks'\nset yrange [0:*]\nset style fill solid 0.6\n"
       << "set boxwidth 0.4\nset key top right\nplot ";
  const char* colours[] = {"#d95f02", "#e7298a", "#66a61e"};
  for (size_t l = 0; l < o.levels.size(); ++l) {
    char title[64];
    std::snprintf(title, sizeof title, "p = %.2f", o.levels[l]);
    plot << (l ? ", " : "") << "$stop" << l << " using ($1 + " << 0.4 * static_cast<double>(l)
         << "):(1) smooth frequency with boxes lc rgb '" << colours[l % 3] << "' title " << gnuplot_quoted(title);
  }
  plot << "\nunset multiplot\n";
  return run_gnuplot(path_stem, data.str(), plot.str(), 1000, 900);
}

}  // namespace hbirl
