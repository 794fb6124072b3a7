#include "services/bus.hpp"

#include <regex.h>

#include <chrono>
#include <cstdio>

#include "learner/input_error.hpp"
#include "services/lcm_bus.hpp"
#include "services/log_bus.hpp"
#include "services/typed.hpp"

namespace hbirl::services {

std::int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

struct ChannelPattern::Compiled {
  regex_t regex;
};

ChannelPattern::ChannelPattern(const std::string& pattern) : compiled_(std::make_unique<Compiled>()) {
  if (regcomp(&compiled_->regex, ("^(" + pattern + ")$").c_str(), REG_EXTENDED | REG_NOSUB) != 0) {
    compiled_.reset();
    throw InputError("channel", "'" + pattern + "' is not a regular expression");
  }
}

ChannelPattern::~ChannelPattern() {
  if (compiled_) regfree(&compiled_->regex);
}

bool ChannelPattern::matches(const std::string& channel) const {
  return regexec(&compiled_->regex, channel.c_str(), 0, nullptr, 0) == 0;
}

std::unique_ptr<Bus> open_bus(const std::string& url) {
  if (url.rfind("log:", 0) == 0) {
    std::string path = url.substr(4), out;
    const size_t q = path.find("?out=");
    if (q != std::string::npos) {
      out = path.substr(q + 5);
      path = path.substr(0, q);
    }
    return std::make_unique<LogBus>(path, out);
  }
  return std::make_unique<LcmBus>(url);
}

void Counters::bad(const std::string& channel, const std::string& why) {
  ++bad_messages;
  last_problem = channel + ": " + why;
  if (!quiet && (bad_messages <= 20 || bad_messages % 1000 == 0)) {
    std::fprintf(stderr, "%s: bad message #%lld on %s: %s\n", service.empty() ? "hbirl" : service.c_str(),
                 static_cast<long long>(bad_messages), printable(channel).c_str(), printable(why).c_str());
  }
}

void Counters::all_refused(const std::string& channel, std::int64_t refused, const std::string& first_reason) {
  const std::string report = std::string(kAllRefusedMarker) + printable(channel) + ": the first " +
                             std::to_string(refused) + ", none accepted; the first: " + printable(first_reason);
  if (all_refused_report.empty()) all_refused_report = report;
  if (!quiet) std::fprintf(stderr, "%s: %s\n", service.empty() ? "hbirl" : service.c_str(), report.c_str());
}

void Counters::note(const std::string& what) const {
  if (!quiet) std::fprintf(stderr, "%s: %s\n", service.empty() ? "hbirl" : service.c_str(), printable(what).c_str());
}

}  // namespace hbirl::services
