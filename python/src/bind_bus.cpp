// Python sensors (bindings.hpp; docs/python.md "Python sensors"): the service set's bus --
// LCM, every message signed with the run's key as the services sign theirs
// (services/keyed_bus.hpp) -- and a sensor that keeps the protocol
// (sim_driver/simulator/live_sensor.hpp). No Python LCM module is needed: the message
// types are hbirl.msg (lcm-gen's Python, packaged), the transport is the services' own.
#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <exception>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "learner/input_error.hpp"
#include "services/keyed_bus.hpp"
#include "services/process.hpp"
#include "sim_driver/simulator/live_sensor.hpp"

namespace hbirl::python {

namespace {

// Python's Ctrl-C while C++ waits: asked for with the GIL every time the wait looks.
bool interrupted() {
  py::gil_scoped_acquire gil;
  return PyErr_CheckSignals() != 0;
}

// The bus: opened on `url` (LCM's default when empty), signed with `key` (a run's key
// file: services/launch.sh's OUT/run.key) when given. Handlers are Python callables of
// (channel, bytes); one that raises stops nothing else, and handle() raises it after.
class PyBus {
 public:
  PyBus(const std::string& url, const std::string& key, const std::string& service) {
    counters_.service = service;
    counters_.quiet = true;
    try {
      bus_ = services::with_key(services::open_bus(url), key, counters_);
    } catch (const InputError& e) {  // named as the Python caller wrote it
      throw InputError(e.field() == "--key"                         ? "key"
                       : e.field() == "--url" || e.field() == "bus" ? "url"
                                                                    : e.field(),
                       e.message());
    }
  }
  services::Bus& bus() { return *bus_; }
  services::Counters& counters() { return counters_; }

  void publish(const std::string& channel, const py::bytes& data) {
    const std::string bytes = data;
    if (channel.empty() || channel.size() > 63) throw InputError("channel", "must be 1 to 63 characters (LCM's limit)");
    if (!bus_->publish(channel, bytes.data(), static_cast<int>(bytes.size())))
      throw InputError("channel", "could not publish on " + channel);
    ++counters_.messages_out;
  }

  services::SubscriptionId subscribe(const std::string& channel, py::function handler) {
    return bus_->subscribe(
        channel,
        [this, handler](const services::Message& m) {
          py::gil_scoped_acquire gil;
          try {
            handler(m.channel, py::bytes(reinterpret_cast<const char*>(m.data), static_cast<size_t>(m.size)));
          } catch (py::error_already_set& e) {
            if (!raised_) raised_ = std::make_unique<py::error_already_set>(std::move(e));
          }
        },
        1000);
  }

  void unsubscribe(services::SubscriptionId id) {
    // (the bus may not drop a handler while it runs it: services/bus.hpp)
    if (handling_) throw InputError("unsubscribe", "not from inside a handler: after handle() returns");
    bus_->unsubscribe(id);
  }

  // `timeout_s`: checked by the package (finite, >= 0, at most 10^6 s).
  int handle(double timeout_s) {
    int handled = 0;
    handling_ = true;
    {
      py::gil_scoped_release released;
      handled = bus_->handle(static_cast<int>(timeout_s * 1000.0));
    }
    handling_ = false;
    if (raised_) {
      const std::unique_ptr<py::error_already_set> e = std::move(raised_);
      throw *e;
    }
    return handled;
  }

 private:
  services::Counters counters_;
  std::unique_ptr<services::Bus> bus_;
  std::unique_ptr<py::error_already_set> raised_;
  bool handling_ = false;
};

// A sensor on a PyBus: LiveSensor, with the service set's heartbeat (STATUS as "sensor").
class PySensor {
 public:
  PySensor(PyBus& bus, const LiveSensorShape& shape)
      : sensor_(bus.bus(), shape, bus.counters()),
        heartbeat_(bus.bus(), bus.counters(), "sensor", services::default_id("sensor")) {
    heartbeat_.tick("starting", true);
  }
  LiveSensor& sensor() { return sensor_; }
  void beat(const std::string& state = "running") { heartbeat_.tick(state); }

 private:
  LiveSensor sensor_;
  services::Heartbeat heartbeat_;
};

std::vector<int> ints(const std::optional<IntArray>& values, const std::string& name) {
  std::vector<int> out;
  if (!values) return out;
  if (values->ndim() != 1) throw InputError(name, "must be one-dimensional");
  const auto* v = values->data();
  for (py::ssize_t i = 0; i < values->size(); ++i) {
    if (v[i] < -(1LL << 31) || v[i] >= (1LL << 31))
      throw InputError(name + "[" + std::to_string(i) + "]", "is out of range");
    out.push_back(static_cast<int>(v[i]));
  }
  return out;
}

RowMatrix eta_rows(const Array& eta, size_t n) {
  if (eta.ndim() != 2 && !(n == 0 && eta.size() == 0))
    throw InputError("eta", "must be two-dimensional (one row per symbol)");
  if (n == 0) return RowMatrix(0, 0);
  return Eigen::Map<const RowMatrix>(eta.data(), eta.shape(0), eta.shape(1));
}

}  // namespace

void bind_bus(py::module_& m) {
  py::class_<PyBus>(m, "_Bus")
      .def(py::init<const std::string&, const std::string&, const std::string&>(), py::arg("url"), py::arg("key"),
           py::arg("service"))
      .def("publish", &PyBus::publish, py::arg("channel"), py::arg("data"))
      .def("subscribe", &PyBus::subscribe, py::arg("channel"), py::arg("handler"))
      .def("unsubscribe", &PyBus::unsubscribe, py::arg("id"))
      .def("handle", &PyBus::handle, py::arg("timeout"))
      .def_property_readonly("authenticated", [](PyBus& b) { return b.counters().authenticated; })
      .def_property_readonly("bad_messages", [](PyBus& b) { return b.counters().bad_messages; });

  py::class_<PySensor>(m, "_Sensor")
      .def(py::init([](PyBus& bus, const std::string& domain, int num_symbols, int num_sources, int num_end_symbols,
                       double step_seconds, const std::optional<Array>& true_weights) {
             LiveSensorShape shape{.domain = domain,
                                   .num_symbols = num_symbols,
                                   .num_sources = num_sources,
                                   .num_end_symbols = num_end_symbols,
                                   .step_seconds = step_seconds,
                                   .true_weights = {}};
             if (true_weights) {
               if (true_weights->ndim() != 1) throw InputError("true_weights", "must be one-dimensional");
               shape.true_weights = Eigen::Map<const Eigen::VectorXd>(true_weights->data(), true_weights->size());
             }
             return std::make_unique<PySensor>(bus, shape);
           }),
           py::arg("bus"), py::arg("domain"), py::arg("num_symbols"), py::arg("num_sources"),
           py::arg("num_end_symbols"), py::arg("step_seconds"), py::arg("true_weights"), py::keep_alive<1, 2>())
      .def(
          "wait_for_optimiser",
          [](PySensor& s, double seconds) {
            bool heard = false;
            {
              py::gil_scoped_release released;
              heard = s.sensor().wait_for_optimiser(seconds, interrupted);
            }
            if (PyErr_Occurred()) throw py::error_already_set();  // Ctrl-C while it waited
            return heard;
          },
          py::arg("seconds"))
      .def(
          "begin_episode",
          [](PySensor& s, bool controlled) {
            s.beat();
            return s.sensor().begin_episode(controlled);
          },
          py::arg("controlled"))
      .def(
          "step",
          [](PySensor& s, const std::optional<IntArray>& symbols, const Array& eta,
             const std::optional<IntArray>& contexts, std::optional<int> state, std::optional<int> action) {
            if (state.has_value() != action.has_value())
              throw InputError(state ? "action" : "state", "give the true state and action together");
            const std::vector<int> w = ints(symbols, "symbols");
            std::optional<StateAction> truth;
            if (state) truth = StateAction{*state, *action};
            s.sensor().step(w, eta_rows(eta, w.size()), ints(contexts, "contexts"), truth);
            s.beat();
            s.sensor().handle(0);  // a FRAME_REQUEST or STOP heard as it comes
          },
          py::arg("symbols"), py::arg("eta"), py::arg("contexts"), py::arg("state"), py::arg("action"))
      .def(
          "end_episode",
          [](PySensor& s, bool ends_in_terminal, int end_state, const std::optional<IntArray>& end_symbols) {
            s.sensor().end_episode(ends_in_terminal, end_state, ints(end_symbols, "end_symbols"));
            s.beat();
          },
          py::arg("ends_in_terminal"), py::arg("end_state"), py::arg("end_symbols"))
      .def("end_run", [](PySensor& s) { s.sensor().end_run(); })
      .def(
          "handle",
          [](PySensor& s, double timeout_s) {  // (seconds checked by the package)
            s.beat();
            py::gil_scoped_release released;
            return s.sensor().handle(static_cast<int>(timeout_s * 1000.0));
          },
          py::arg("timeout"))
      .def(
          "wait_for_reward",
          [](PySensor& s, double seconds) -> std::optional<std::vector<double>> {
            std::optional<Eigen::VectorXd> theta;
            {
              py::gil_scoped_release released;
              theta = s.sensor().wait_for_reward(seconds, interrupted);
            }
            s.beat(theta ? "done" : "running");
            if (!theta && PyErr_Occurred()) throw py::error_already_set();
            if (!theta) return std::nullopt;
            return std::vector<double>(theta->data(), theta->data() + theta->size());
          },
          py::arg("seconds"))
      .def_property_readonly("stop_requested", [](PySensor& s) { return s.sensor().stop_requested(); })
      .def_property_readonly("episodes", [](PySensor& s) { return s.sensor().episodes(); })
      .def_property_readonly("in_episode", [](PySensor& s) { return s.sensor().in_episode(); })
      .def_property_readonly("run_ended", [](PySensor& s) { return s.sensor().run_ended(); })
      .def_property_readonly("frames_resent", [](PySensor& s) { return s.sensor().frames_resent(); });
}

}  // namespace hbirl::python
