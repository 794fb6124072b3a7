#include <cerrno>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "app/learn_settings.hpp"
#include "commands.hpp"
#include "learner/input_error.hpp"

namespace hbirl::cli {

void emit(const std::string& text, const std::string& path) {
  emit_streamed([&text](std::ostream& out) { out << text; }, path);
}

void emit_streamed(const std::function<void(std::ostream&)>& write, const std::string& path) {
  if (path.empty()) {
    errno = 0;
    write(std::cout);
    std::cout << std::flush;
    if (!std::cout) throw OutputError(std::string("stdout: ") + std::strerror(errno ? errno : EIO));
    return;
  }
  std::ofstream out(path, std::ios::binary);
  write(out);
  out.flush();
  if (!out) throw InputError("--out", "cannot write " + path);
}

void warn_all(const std::string& source, const std::vector<std::string>& warnings) {
  for (const auto& w : warnings) std::cerr << "hbirl: warning: " << printable(source + ": " + w) << "\n";
}

}  // namespace hbirl::cli

namespace hbirl::cli {

Problem load_problem(const std::string& path) {
  std::vector<std::string> warnings;
  try {
    Problem problem = read_problem_file(path, &warnings);
    warn_all(path, warnings);
    return problem;
  } catch (const FileError& e) {
    throw InputError("--problem " + path, e.message());  // not a file it can read: say which option gave it
  } catch (const InputError& e) {
    throw in_file(path, e);
  }
}

InputError in_file(const std::string& path, const InputError& e) {
  return InputError(e.field().empty() ? path : path + ": " + e.field(), e.message());
}

}  // namespace hbirl::cli

namespace hbirl::cli {

nlohmann::ordered_json mcmc_diagnostics_json(const McmcDiagnostics& diagnostics) {
  nlohmann::ordered_json out;
  const bool checked = diagnostics.quantities > 0;
  out["worst_rhat"] = checked ? nlohmann::ordered_json(diagnostics.worst_rhat) : nlohmann::ordered_json(nullptr);
  out["worst_bulk_ess"] =
      checked ? nlohmann::ordered_json(diagnostics.worst_bulk_ess) : nlohmann::ordered_json(nullptr);
  out["quantities"] = diagnostics.quantities;
  out["chains"] = diagnostics.chains;
  return out;
}

void warn_if_not_converged(const McmcDiagnostics& diagnostics) {
  if (diagnostics.converged()) return;
  std::ostringstream line;
  line << std::fixed << "hbirl: warning: MCMC not converged:";
  const char* separator = " ";
  if (!(diagnostics.worst_rhat <= kRhatThreshold)) {
    line << separator << "R\u0302 " << std::setprecision(3) << diagnostics.worst_rhat << " > " << std::setprecision(2)
         << kRhatThreshold;
    separator = ", ";
  }
  if (!(diagnostics.worst_bulk_ess >= kBulkEssThreshold)) {
    line << separator << "bulk ESS " << std::setprecision(0) << diagnostics.worst_bulk_ess << " < "
         << kBulkEssThreshold;
  }
  line << " (worst of " << diagnostics.quantities << " pair marginals, " << diagnostics.chains
       << " chains each); raise --mcmc-samples or --mcmc-chains\n";
  std::cerr << line.str();
}

}  // namespace hbirl::cli

namespace hbirl::cli {

CLI::Option* add_alpha_update_option(CLI::App* cmd, AlphaUpdate& update) {
  const std::map<std::string, AlphaUpdate> names{{"posterior", AlphaUpdate::kPosterior},
                                                 {"paper", AlphaUpdate::kPaper}};
  return cmd
      ->add_option("--alpha-update", update, app::learn_setting("alpha_update").help)  // hbirl learn's words
      ->transform(CLI::CheckedTransformer(names))
      ->default_str("posterior")
      ->option_text("{posterior,paper}=posterior");  // not CLI11's "ENUM:value in {paper->1,...}"
}

}  // namespace hbirl::cli
