// Summaries and figures of the eta-sensitivity and unlisted-confounder experiments
// (eta_experiments.hpp; docs/results/eta_sensitivity, docs/results/unlisted).
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "experiments/eta_experiments.hpp"
#include "experiments/summary.hpp"

namespace hbirl {

namespace {

std::string number(double x, int precision = 3) {
  std::ostringstream out;
  out.precision(precision);
  out << x;
  return out.str();
}

std::string mean_ci(const std::vector<double>& values, int precision = 3) {
  const SummaryRow r = mean_and_ci(values);
  return r.n == 0 ? "–" : number(r.mean, precision) + " ± " + number(r.ci95, 2);
}

// (confounders, mass, accuracy, method) -> ILE of each successful run, by run index.
using EtaKey = std::tuple<int, double, double, std::string>;
std::map<EtaKey, std::map<int, double>> eta_cells(const std::vector<EtaRun>& runs, double EtaRun::*field) {
  std::map<EtaKey, std::map<int, double>> cells;
  for (const EtaRun& r : runs) {
    if (r.error.empty()) cells[{r.confounders, r.mass, r.accuracy, r.method}][r.run] = r.*field;
  }
  return cells;
}

std::vector<double> values_of(const std::map<int, double>& by_run) {
  std::vector<double> v;
  for (const auto& [run, x] : by_run) v.push_back(x);
  return v;
}

// fixed - learned over the runs both finished.
std::vector<double> paired_gain(const std::map<int, double>& fixed, const std::map<int, double>& learned) {
  std::vector<double> d;
  for (const auto& [run, x] : fixed) {
    if (const auto it = learned.find(run); it != learned.end()) d.push_back(x - it->second);
  }
  return d;
}

int failed_runs(const std::vector<EtaRun>& runs) {
  return static_cast<int>(std::count_if(runs.begin(), runs.end(), [](const EtaRun& r) { return !r.error.empty(); }));
}

}  // namespace

std::string eta_sensitivity_summary(const std::vector<EtaRun>& runs, const std::string& footer) {
  const auto ile = eta_cells(runs, &EtaRun::ile);
  const auto subject_eta = eta_cells(runs, &EtaRun::subject_eta);
  std::set<int> confounders;
  std::set<double> masses, accuracies;
  for (const EtaRun& r : runs) {
    confounders.insert(r.confounders);
    if (r.method != "perfect") masses.insert(r.mass), accuracies.insert(r.accuracy);
  }
  std::ostringstream md;
  md << "# eta sensitivity: a labeller that claims more (or less) than it knows\n\n"
     << "The labeller gives its pick a share m of eta (what it claims) and picks the true source with probability q "
        "(what it knows); perfectly calibrated when m = q. Mean ILE ± 95% CI per cell, eta as stated (fixed) → "
        "eta learned per context (learned).\n";
  for (int e : confounders) {
    const auto perfect = ile.find({e, 1.0, 1.0, "perfect"});
    const std::vector<double> perfect_ile = perfect == ile.end() ? std::vector<double>{} : values_of(perfect->second);
    const double reference = mean_and_ci(perfect_ile).mean;
    md << "\n## |E| = " << e << "\n\nA perfect labeller (all of eta on the true source): ILE " << mean_ci(perfect_ile)
       << ".\n\n";
    md << "| m \\ q |";
    for (double q : accuracies) md << " " << number(q) << " |";
    md << "\n|---|";
    for (size_t i = 0; i < accuracies.size(); ++i) md << "---|";
    md << "\n";
    double fixed_gap = 0.0, learned_gap = 0.0;
    int better = 0, worse = 0, cells = 0;
    for (double m : masses) {
      md << "| " << number(m) << " |";
      for (double q : accuracies) {
        const auto f = ile.find({e, m, q, "fixed"});
        const auto l = ile.find({e, m, q, "learned"});
        if (f == ile.end() || l == ile.end()) {
          md << " – |";
          continue;
        }
        const SummaryRow fixed = mean_and_ci(values_of(f->second));
        const SummaryRow learned = mean_and_ci(values_of(l->second));
        const SummaryRow gain = mean_and_ci(paired_gain(f->second, l->second));
        md << " " << number(fixed.mean) << " → " << number(learned.mean) << " |";
        ++cells;
        better += gain.mean - gain.ci95 > 0.0;
        worse += gain.mean + gain.ci95 < 0.0;
        fixed_gap += fixed.mean - reference;
        learned_gap += learned.mean - reference;
      }
      md << "\n";
    }
    md << "\nLearned eta is better (the 95% CI of the paired difference above 0) in " << better << " of " << cells
       << " cells and worse in " << worse << ". Summed over the cells, the gap to the perfect labeller is "
       << number(fixed_gap) << " with fixed eta and " << number(learned_gap) << " with learned eta: learned eta closes "
       << (fixed_gap > 0.0 ? number(100.0 * (1.0 - learned_gap / fixed_gap), 3) + "%" : std::string("– (no gap)"))
       << " of it.\n";
    md << "\nLearned eta's subject share for the context \"the labeller picked the subject\" (the truth is q):\n\n| m "
          "\\ q |";
    for (double q : accuracies) md << " " << number(q) << " |";
    md << "\n|---|";
    for (size_t i = 0; i < accuracies.size(); ++i) md << "---|";
    md << "\n";
    for (double m : masses) {
      md << "| " << number(m) << " |";
      for (double q : accuracies) {
        const auto s = subject_eta.find({e, m, q, "learned"});
        md << " " << (s == subject_eta.end() ? std::string("–") : mean_ci(values_of(s->second), 2)) << " |";
      }
      md << "\n";
    }
  }
  md << "\n" << footer;
  if (const int failed = failed_runs(runs))
    md << " " << failed << " runs failed and are left out (see the error column).";
  md << "\n";
  return md.str();
}

std::string draw_eta_sensitivity_figure(const std::vector<EtaRun>& runs, const std::string& path_stem) {
  const auto ile = eta_cells(runs, &EtaRun::ile);
  std::set<int> confounders;
  std::vector<double> masses, accuracies;
  for (const EtaRun& r : runs) {
    confounders.insert(r.confounders);
    if (r.method == "perfect") continue;
    if (std::find(masses.begin(), masses.end(), r.mass) == masses.end()) masses.push_back(r.mass);
    if (std::find(accuracies.begin(), accuracies.end(), r.accuracy) == accuracies.end())
      accuracies.push_back(r.accuracy);
  }
  std::sort(masses.begin(), masses.end());
  std::sort(accuracies.begin(), accuracies.end());
  // One heat map per (|E|, method): x the accuracy q, y the mass m, colour the mean ILE.
  std::ostringstream data;
  double top = 0.0;
  std::vector<std::string> panels;
  for (int e : confounders) {
    for (const char* method : {"fixed", "learned"}) {
      const std::string block = "$e" + std::to_string(e) + method;
      data << block << " << EOD\n";
      for (size_t y = 0; y < masses.size(); ++y) {
        for (size_t x = 0; x < accuracies.size(); ++x) {
          const auto c = ile.find({e, masses[y], accuracies[x], method});
          const double mean = c == ile.end() ? NAN : mean_and_ci(values_of(c->second)).mean;
          if (std::isfinite(mean)) top = std::max(top, mean);
          data << x << " " << y << " " << mean << "\n";
        }
        data << "\n";
      }
      data << "EOD\n";
      panels.push_back(block + "|" + "|E| = " + std::to_string(e) + ", eta " +
                       (std::string(method) == "fixed" ? "as stated" : "learned"));
    }
  }
  data << "set xtics (";
  for (size_t x = 0; x < accuracies.size(); ++x) data << (x ? ", " : "") << "'" << number(accuracies[x]) << "' " << x;
  data << ")\nset ytics (";
  for (size_t y = 0; y < masses.size(); ++y) data << (y ? ", " : "") << "'" << number(masses[y]) << "' " << y;
  data << ")\nset xlabel 'q: probability the labeller picks the true source'\nset ylabel 'm: share of eta it gives its "
          "pick'\n"
       << "set cbrange [0:" << std::max(top, 1e-9)
       << "]\nset cblabel 'mean ILE'\nset palette defined (0 '#f7fbff', 0.5 '#6baed6', 1 '#08306b')\n"
       << "set xrange [-0.5:" << static_cast<double>(accuracies.size()) - 0.5
       << "]\nset yrange [-0.5:" << static_cast<double>(masses.size()) - 0.5 << "]\nunset key\n";
  std::ostringstream plot;
  plot << "set multiplot layout " << confounders.size()
       << ",2 title 'ILE with a miscalibrated labeller (calibrated on the diagonal m = q)'\n";
  for (const std::string& p : panels) {
    const size_t bar = p.find('|');
    plot << "set title " << gnuplot_quoted(p.substr(bar + 1)) << "\nplot " << p.substr(0, bar)
         << " using 1:2:3 with image, " << p.substr(0, bar)
         << " using 1:2:(sprintf('%.1f', $3)) with labels textcolor rgb '#d95f02'\n";
  }
  plot << "unset multiplot\n";
  return run_gnuplot(path_stem, data.str(), plot.str(), 1000,
                     420 * static_cast<int>(std::max<size_t>(1, confounders.size())));
}

namespace {

const std::vector<std::string>& unlisted_methods() {
  static const std::vector<std::string> m = {"as_told", "catch_all", "catch_all_learned_eta", "oracle"};
  return m;
}

std::string unlisted_label(const std::string& method) {
  if (method == "as_told") return "as told";
  if (method == "catch_all") return "catch-all, eta fixed";
  if (method == "catch_all_learned_eta") return "catch-all, eta learned";
  return "oracle (told every element)";
}

// (told, method, |E|) -> values; the oracle under every told (it is told everything).
std::map<std::tuple<int, std::string, int>, std::vector<double>> unlisted_cells(const std::vector<UnlistedRun>& runs,
                                                                                double UnlistedRun::*field) {
  std::set<int> told;
  for (const UnlistedRun& r : runs) {
    if (r.method != "oracle") told.insert(r.told);
  }
  std::map<std::tuple<int, std::string, int>, std::vector<double>> cells;
  for (const UnlistedRun& r : runs) {
    if (!r.error.empty()) continue;
    if (r.method == "oracle") {
      for (int t : told) cells[{t, r.method, r.confounders}].push_back(r.*field);
    } else {
      cells[{r.told, r.method, r.confounders}].push_back(r.*field);
    }
  }
  return cells;
}

std::string told_name(int told) {
  return told == 0 ? "told none (eta over the subject alone)" : "told " + std::to_string(told) + " element(s)";
}

}  // namespace

std::string unlisted_summary(const std::vector<UnlistedRun>& runs, const std::string& footer) {
  std::set<int> told, confounders;
  for (const UnlistedRun& r : runs) {
    confounders.insert(r.confounders);
    if (r.method != "oracle") told.insert(r.told);
  }
  std::ostringstream md;
  md << "# Unlisted confounders: ILE and label accuracy vs the number of true elements\n";
  for (const auto& [what, field] : {std::pair<std::string, double UnlistedRun::*>{"ILE", &UnlistedRun::ile},
                                    std::pair<std::string, double UnlistedRun::*>{"label accuracy (subject or not)",
                                                                                  &UnlistedRun::label_accuracy}}) {
    const auto cells = unlisted_cells(runs, field);
    for (int t : told) {
      md << "\n## " << what << ", " << told_name(t) << "\n\n| method |";
      for (int e : confounders) md << " |E| = " << e << " |";
      md << "\n|---|";
      for (size_t i = 0; i < confounders.size(); ++i) md << "---|";
      md << "\n";
      for (const std::string& m : unlisted_methods()) {
        md << "| " << unlisted_label(m) << " |";
        for (int e : confounders) {
          const auto c = cells.find({t, m, e});
          md << " " << (c == cells.end() ? std::string("–") : mean_ci(c->second)) << " |";
        }
        md << "\n";
      }
    }
  }
  md << "\n" << footer << "\n";
  return md.str();
}

std::string draw_unlisted_figure(const std::vector<UnlistedRun>& runs, const std::string& path_stem) {
  std::set<int> told, confounders;
  for (const UnlistedRun& r : runs) {
    confounders.insert(r.confounders);
    if (r.method != "oracle") told.insert(r.told);
  }
  std::ostringstream data, plot;
  const std::vector<std::pair<std::string, double UnlistedRun::*>> panels = {
      {"ILE", &UnlistedRun::ile}, {"label accuracy", &UnlistedRun::label_accuracy}};
  for (size_t p = 0; p < panels.size(); ++p) {
    const auto cells = unlisted_cells(runs, panels[p].second);
    for (int t : told) {
      for (size_t m = 0; m < unlisted_methods().size(); ++m) {
        data << "$p" << p << "t" << t << "m" << m << " << EOD\n";
        for (int e : confounders) {
          const auto c = cells.find({t, unlisted_methods()[m], e});
          if (c == cells.end()) continue;
          const SummaryRow r = mean_and_ci(c->second);
          data << e << " " << r.mean << " " << r.ci95 << "\n";
        }
        data << "EOD\n";
      }
    }
  }
  data << "set grid\nset key box opaque\nset offsets 0.3, 0.3, 0, 0\nset xlabel 'true confounding elements |E|'\n"
       << "set style line 1 lc rgb '#1b9e77' lw 2 pt 7\nset style line 2 lc rgb '#d95f02' lw 2 pt 5\n"
       << "set style line 3 lc rgb '#7570b3' lw 2 pt 9\nset style line 4 lc rgb '#666666' lw 2 pt 11 dt 2\n";
  plot << "set multiplot layout " << panels.size() << "," << told.size() << " title 'Unlisted confounders (95% CI)'\n";
  for (size_t p = 0; p < panels.size(); ++p) {
    for (int t : told) {
      plot << "set title " << gnuplot_quoted(panels[p].first + ", " + told_name(t)) << "\nset ylabel "
           << gnuplot_quoted(panels[p].first) << "\n"
           << (p == 0 ? "set yrange [0:*]\nset key top left\n" : "set yrange [0:1.02]\nset key bottom left\n")
           << "plot ";
      for (size_t m = 0; m < unlisted_methods().size(); ++m) {
        plot << (m ? ", " : "") << "$p" << p << "t" << t << "m" << m << " using 1:2:3 with yerrorlines ls " << m + 1
             << " title " << gnuplot_quoted(unlisted_label(unlisted_methods()[m]));
      }
      plot << "\n";
    }
  }
  plot << "unset multiplot\n";
  return run_gnuplot(path_stem, data.str(), plot.str(), 1100, 800);
}

}  // namespace hbirl
