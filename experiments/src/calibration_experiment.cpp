#include "experiments/calibration_experiment.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>

#include "app/learn.hpp"
#include "experiments/judged_tasks.hpp"
#include "experiments/summary.hpp"
#include "learner/input_error.hpp"
#include "learner/metrics.hpp"
#include "learner/parallel.hpp"
#include "plot/gnuplot.hpp"

namespace hbirl {

namespace {

constexpr int kBins = 10;
constexpr double kConfident = 0.9;

// The first n demonstrations of `all` (n = 0: every one).
template <class T>
std::vector<T> first(const std::vector<T>& all, int n) {
  if (n == 0) return all;
  return std::vector<T>(all.begin(), all.begin() + n);
}

// One data set learned as `hbirl learn --posterior-samples` learns it, one thread per run,
// from its first r.demonstrations demonstrations.
void learn_and_score(const JudgedTask& task, const DataSetId& id, const CalibrationOptions& o, CalibrationRun& r) {
  const int n = r.demonstrations;
  if (n > static_cast<int>(task.truth.size())) {
    throw InputError("demonstrations",
                     std::to_string(n) + " asked, the data set has " + std::to_string(task.truth.size()));
  }
  app::LearnSettings settings;
  settings.em.threads = 1;
  settings.em.seed = id.seed * 1000003ull + static_cast<std::uint64_t>(id.draw);
  settings.posterior.samples = o.samples;
  settings.posterior.prior_scale = o.prior_scale;
  const app::Learned learned = r.data == "truth" ? app::learn_from_truth(task.mdp, first(task.truth, n), settings)
                                                 : app::learn(task.mdp, first(task.observed, n), task.prior, settings);
  r.confidence = learned.confidence->near_optimal;
  r.probability_optimal = learned.confidence->optimal;
  r.expected_ile_relative = learned.confidence->expected_relative_ile;
  r.ile_relative = inverse_learning_error(task.mdp, task.true_weights, learned.em.theta).relative();
  r.right = r.ile_relative <= kNearOptimalShare;
  r.prior_scale = learned.posterior->prior_scale;
  r.effective_samples = learned.posterior->effective_samples;
}

std::vector<const CalibrationRun*> runs_of(const std::vector<CalibrationRun>& runs, const std::string& data) {
  std::vector<const CalibrationRun*> out;
  for (const CalibrationRun& r : runs) {
    if (r.data == data && r.error.empty()) out.push_back(&r);
  }
  return out;
}

CalibrationScore score_of(const std::vector<const CalibrationRun*>& runs) {
  std::vector<double> confidence;
  std::vector<bool> right;
  for (const CalibrationRun* r : runs) {
    confidence.push_back(r->confidence);
    right.push_back(r->right);
  }
  return calibration_score(confidence, right);
}

std::vector<std::string> data_in(const std::vector<CalibrationRun>& runs) {
  std::vector<std::string> out;
  for (const std::string d : {"observations", "truth"}) {
    if (!runs_of(runs, d).empty()) out.push_back(d);
  }
  return out;
}

// The area under the ROC curve: the share of (right, wrong) pairs the confidence orders
// right, ties counting half (Mann-Whitney), by one sort.
double auroc(const std::vector<double>& p, const std::vector<bool>& y) {
  std::vector<size_t> order(p.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return p[a] < p[b]; });
  double wrong_below = 0.0, pairs_right = 0.0;
  double right_total = 0.0, wrong_total = 0.0;
  for (size_t i = 0; i < order.size();) {
    size_t j = i;
    double right_here = 0.0, wrong_here = 0.0;
    for (; j < order.size() && p[order[j]] == p[order[i]]; ++j) (y[order[j]] ? right_here : wrong_here) += 1.0;
    pairs_right += right_here * (wrong_below + 0.5 * wrong_here);
    wrong_below += wrong_here;
    right_total += right_here;
    wrong_total += wrong_here;
    i = j;
  }
  return right_total > 0.0 && wrong_total > 0.0 ? pairs_right / (right_total * wrong_total) : 0.5;
}

// The learned-from prefix lengths in `runs`, in order (one entry, 0, when every run learned from all).
std::vector<int> prefixes_in(const std::vector<CalibrationRun>& runs) {
  std::vector<int> out;
  for (const CalibrationRun& r : runs) {
    if (std::find(out.begin(), out.end(), r.demonstrations) == out.end()) out.push_back(r.demonstrations);
  }
  std::sort(out.begin(), out.end());
  return out;
}

void write_score_row(std::ostream& out, const std::string& label, const CalibrationScore& s) {
  char buf[300];
  std::snprintf(buf, sizeof buf, "| %s | %d | %d (%.1f%%) | %.3f | %.3f | %.3f | %.3f | %d of %d (%.1f%%) |\n",
                label.c_str(), s.runs, s.right, 100.0 * s.right / std::max(1, s.runs), s.mean_confidence, s.auroc,
                s.ece, s.brier, s.confident_right, s.confident, 100.0 * s.confident_right / std::max(1, s.confident));
  out << buf;
}

// Per data, and per prefix length when the runs learned from several (--demonstrations).
void write_score_table(std::ostream& out, const std::vector<CalibrationRun>& runs) {
  out << "| data | runs | right | mean confidence | AUROC | ECE | Brier | confidence >= 0.9: right |\n"
      << "|---|---|---|---|---|---|---|---|\n";
  const std::vector<int> prefixes = prefixes_in(runs);
  for (const std::string& d : data_in(runs)) {
    const std::vector<const CalibrationRun*> of_d = runs_of(runs, d);
    write_score_row(out, prefixes.size() > 1 ? d + ", all" : d, score_of(of_d));
    if (prefixes.size() < 2) continue;
    for (int n : prefixes) {
      std::vector<const CalibrationRun*> of_n;
      for (const CalibrationRun* r : of_d) {
        if (r->demonstrations == n) of_n.push_back(r);
      }
      write_score_row(out, d + ", the first " + std::to_string(n), score_of(of_n));
    }
  }
}

void write_reliability_table(std::ostream& out, const std::vector<CalibrationRun>& runs) {
  for (const std::string& d : data_in(runs)) {
    const CalibrationScore s = score_of(runs_of(runs, d));
    out << "\nReliability, from " << d << ":\n\n| confidence | runs | mean confidence | share right [95% Wilson] |\n"
        << "|---|---|---|---|\n";
    for (const ReliabilityBin& b : s.bins) {
      if (b.runs == 0) continue;
      const auto [lo, hi] = wilson(b.right, b.runs);
      char buf[200];
      std::snprintf(buf, sizeof buf, "| %.1f-%.1f | %d | %.3f | %.3f [%.3f, %.3f] |\n", b.lo, b.hi, b.runs,
                    b.mean_confidence, static_cast<double>(b.right) / b.runs, lo, hi);
      out << buf;
    }
  }
}

// The confident and wrong: where the promise was broken, worst first.
void write_confident_wrong(std::ostream& out, const std::vector<CalibrationRun>& runs) {
  std::vector<const CalibrationRun*> wrong;
  for (const CalibrationRun& r : runs) {
    if (r.error.empty() && !r.right && r.confidence >= kConfident) wrong.push_back(&r);
  }
  std::sort(wrong.begin(), wrong.end(),
            [](const CalibrationRun* a, const CalibrationRun* b) { return a->confidence > b->confidence; });
  out << "\nConfidence >= 0.9 and wrong: " << wrong.size() << " runs";
  if (wrong.empty()) {
    out << ".\n";
    return;
  }
  out << " (seed/draw/demonstrations (0: all) data: confidence, relative ILE):";
  const size_t shown = std::min<size_t>(wrong.size(), 20);
  for (size_t i = 0; i < shown; ++i) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s %llu/%d/%d %s: %.3f, %.3f", i ? ";" : "",
                  static_cast<unsigned long long>(wrong[i]->seed), wrong[i]->draw, wrong[i]->demonstrations,
                  wrong[i]->data.c_str(), wrong[i]->confidence, wrong[i]->ile_relative);
    out << buf;
  }
  out << (shown < wrong.size() ? "; ...\n" : ".\n");
}

}  // namespace

CalibrationScore calibration_score(const std::vector<double>& confidence, const std::vector<bool>& right) {
  CalibrationScore s;
  s.runs = static_cast<int>(confidence.size());
  for (int b = 0; b < kBins; ++b) {
    ReliabilityBin bin;
    bin.lo = static_cast<double>(b) / kBins;
    bin.hi = static_cast<double>(b + 1) / kBins;
    s.bins.push_back(bin);
  }
  if (s.runs == 0) return s;
  for (size_t i = 0; i < confidence.size(); ++i) {
    const double p = confidence[i];
    const int y = right[i] ? 1 : 0;
    s.right += y;
    s.mean_confidence += p;
    s.brier += (p - y) * (p - y);
    if (p >= kConfident) {
      ++s.confident;
      s.confident_right += y;
    }
    ReliabilityBin& bin = s.bins[static_cast<size_t>(std::clamp(static_cast<int>(p * kBins), 0, kBins - 1))];
    ++bin.runs;
    bin.right += y;
    bin.mean_confidence += p;
  }
  s.mean_confidence /= s.runs;
  s.brier /= s.runs;
  for (ReliabilityBin& bin : s.bins) {
    if (bin.runs == 0) continue;
    bin.mean_confidence /= bin.runs;
    s.ece += static_cast<double>(bin.runs) / s.runs *
             std::abs(bin.mean_confidence - static_cast<double>(bin.right) / bin.runs);
  }
  s.auroc = auroc(confidence, right);
  return s;
}

std::vector<CalibrationRun> run_calibration(const CalibrationOptions& o) {
  if (o.data.empty()) throw InputError("data", "none to learn from");
  for (int n : o.demonstrations) {
    if (n < 1) throw InputError("demonstrations", "each must be at least 1");
  }
  // Per data set, for each prefix n (or all), each data: variant v = prefix * |data| + data.
  const std::vector<int> prefixes = o.demonstrations.empty() ? std::vector<int>{0} : o.demonstrations;
  const size_t variants = prefixes.size() * o.data.size();
  return on_judged_tasks<CalibrationRun>({o.tasks_from, o.tasks, o.first_seed, o.draws}, variants, o.threads,
                                         o.progress, [&](const JudgedTask& task, size_t v, CalibrationRun& run) {
                                           run.demonstrations = prefixes[v / o.data.size()];
                                           run.data = o.data[v % o.data.size()];
                                           learn_and_score(task, {run.seed, run.draw}, o, run);
                                         });
}

std::string calibration_runs_csv(const std::vector<CalibrationRun>& runs) {
  std::ostringstream out;
  out.precision(10);
  out << "seed,draw,demonstrations,data,confidence,probability_optimal,expected_ile_relative,ile_relative,right,prior_"
         "scale,"
         "effective_samples,seconds,error\n";
  for (const CalibrationRun& r : runs) {
    out << r.seed << "," << r.draw << "," << r.demonstrations << "," << r.data << "," << r.confidence << ","
        << r.probability_optimal << "," << r.expected_ile_relative << "," << r.ile_relative << "," << (r.right ? 1 : 0)
        << "," << r.prior_scale << "," << r.effective_samples << "," << r.seconds << "," << csv_text(r.error) << "\n";
  }
  return out.str();
}

std::vector<CalibrationRun> calibration_runs_from_csv(const std::string& csv) {
  std::istringstream in(csv);
  std::string line;
  if (!std::getline(in, line) || line + "\n" != calibration_runs_csv({})) {
    throw InputError("runs CSV", "line 1: not a calibration_runs.csv header");
  }
  std::vector<CalibrationRun> runs;
  for (int number = 2; std::getline(in, line); ++number) {
    const std::vector<std::string> f = csv_cells(line);
    if (f.size() != 13) {
      throw InputError("runs CSV",
                       "line " + std::to_string(number) + ": " + std::to_string(f.size()) + " fields, expected 13");
    }
    try {
      CalibrationRun r;
      r.seed = std::stoull(f[0]);
      r.draw = std::stoi(f[1]);
      r.demonstrations = std::stoi(f[2]);
      r.data = f[3];
      size_t i = 4;
      for (double* x : {&r.confidence, &r.probability_optimal, &r.expected_ile_relative, &r.ile_relative})
        *x = std::stod(f[i++]);
      r.right = f[i++] == "1";
      for (double* x : {&r.prior_scale, &r.effective_samples, &r.seconds}) *x = std::stod(f[i++]);
      r.error = f[i];
      runs.push_back(std::move(r));
    } catch (const std::logic_error&) {
      throw InputError("runs CSV", "line " + std::to_string(number) + ": a field is not a number");
    }
  }
  return runs;
}

std::string calibration_summary(const std::vector<CalibrationRun>& runs, const std::string& footer) {
  std::ostringstream out;
  out << "# Calibration: is the confidence a promise?\n\n"
      << "The confidence is the posterior probability that the learned reward's optimal policy is within 5% of the "
         "optimal value; a run is right when it is (relative ILE <= 0.05 under the true reward). Targets: AUROC >= "
         "0.85, ECE <= 0.05, and of the runs with confidence >= 0.9 at least 90% right.\n\n";
  write_score_table(out, runs);
  write_reliability_table(out, runs);
  write_confident_wrong(out, runs);
  const long failed = std::count_if(runs.begin(), runs.end(), [](const CalibrationRun& r) { return !r.error.empty(); });
  if (failed > 0) out << "\n" << failed << " runs failed (their error is in calibration_runs.csv).\n";
  out << "\n" << footer << "\n";
  return out.str();
}

std::string draw_calibration_figure(const std::vector<CalibrationRun>& runs, const std::string& path_stem) {
  const std::vector<std::string> data = data_in(runs);
  if (data.empty()) return "no runs";
  std::ostringstream blocks;
  for (size_t d = 0; d < data.size(); ++d) {
    const CalibrationScore s = score_of(runs_of(runs, data[d]));
    blocks << "$d" << d << " << EOD\n";
    for (const ReliabilityBin& b : s.bins) {
      if (b.runs == 0) continue;
      const auto [lo, hi] = wilson(b.right, b.runs);
      blocks << b.mean_confidence << " " << static_cast<double>(b.right) / b.runs << " " << lo << " " << hi << " "
             << 0.5 * (b.lo + b.hi) << " " << b.runs << "\n";
    }
    blocks << "EOD\n";
  }
  const char* colours[] = {"#d95f02", "#1b9e77"};
  std::ostringstream plot;
  plot << "set multiplot layout 2,1\nset size 1,0.7\nset origin 0,0.3\nset grid\nset key left top\n"
       << "set xrange [0:1]\nset yrange [0:1]\nset xlabel 'confidence (mean in bin)'\nset ylabel 'share right'\n"
       << "set title 'Reliability: share of runs within 5% of the optimal value against the confidence (95% "
          "Wilson)'\nplot x title 'calibrated' lc rgb '#888888' dt 2";
  for (size_t d = 0; d < data.size(); ++d) {
    const CalibrationScore s = score_of(runs_of(runs, data[d]));
    char title[160];
    std::snprintf(title, sizeof title, "from %s (ECE %.3f, AUROC %.3f)", data[d].c_str(), s.ece, s.auroc);
    plot << ", $d" << d << " using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '" << colours[d % 2] << "' title "
         << gnuplot_quoted(title);
  }
  plot << "\nset size 1,0.3\nset origin 0,0\nset title 'Runs per confidence bin'\nset xlabel 'confidence'\n"
       << "set ylabel 'runs'\nset yrange [0:*]\nset style fill solid 0.6\nset boxwidth 0.04\nplot ";
  for (size_t d = 0; d < data.size(); ++d) {
    plot << (d ? ", " : "") << "$d" << d << " using ($5" << (d ? "+0.02" : "-0.02") << "):6 with boxes lc rgb '"
         << colours[d % 2] << "' title " << gnuplot_quoted(data[d]);
  }
  plot << "\nunset multiplot\n";
  return run_gnuplot(path_stem, blocks.str(), plot.str(), 1000, 1100);
}

}  // namespace hbirl
