#pragma once
// Summaries and figures of experiment runs: mean and 95% confidence interval per
// (method, x) and a paper-style figure drawn by gnuplot.
#include <chrono>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "plot/gnuplot.hpp"

namespace hbirl {

struct SummaryRow {
  std::string method;
  int x = 0;
  int n = 0;
  double mean = 0.0;
  double sd = 0.0;
  double ci95 = 0.0;  // half-width: t_{0.975, n-1} * sd / sqrt(n)
};

// A free-text field (an error message) made safe for one CSV cell: commas become ';',
// newlines spaces.
std::string csv_text(std::string text);
// The cells of one line of a runs CSV (a trailing comma ends with an empty cell).
std::vector<std::string> csv_cells(const std::string& line);

// The mean, standard deviation and 95% t-interval of `values` (method and x left empty).
SummaryRow mean_and_ci(const std::vector<double>& values);

// One learning run of an experiment: `learn(run)`, timed into run.seconds, what it throws
// kept in run.error (one failed run must not lose the others).
template <class Run, class Learn>
void record_run(Run& run, Learn&& learn) {
  const auto start = std::chrono::steady_clock::now();
  try {
    learn(run);
  } catch (const std::exception& e) {
    run.error = e.what();
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The 95% Wilson score interval of a proportion k / n ([0, 1] when n is 0).
std::pair<double, double> wilson(int k, int n);

// values[i] belongs to (methods[i], xs[i]); rows come out ordered by method (first
// appearance) then x.
std::vector<SummaryRow> summarise(const std::vector<std::string>& methods, const std::vector<int>& xs,
                                  const std::vector<double>& values);

std::string summary_csv(const std::vector<SummaryRow>& rows, const std::string& x_name);
std::string summary_markdown(const std::vector<SummaryRow>& rows, const std::string& x_name,
                             const std::string& value_name);

struct FigureSpec {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::string path_stem;  // writes <stem>.gp, <stem>.png and <stem>.svg
};

// Writes the gnuplot script and runs gnuplot on it. Returns an empty string on success,
// else why the figure was not drawn (gnuplot missing or failing); the script is kept.
std::string draw_figure(const std::vector<SummaryRow>& rows, const FigureSpec& spec);

}  // namespace hbirl
