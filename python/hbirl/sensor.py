"""Python sensors for hbirl's service set (docs/python.md "Python sensors"), with nothing but
`import hbirl`: the message types (hbirl.msg, lcm-gen's Python), the bus the services use
(LCM, each message signed with the run's key as theirs are), and a Sensor that keeps the
protocol -- episode markers, one OBSERVATIONS message per step, the controlled run's
ground truth, lost steps and end markers sent again when the optimiser asks, the end of
the run repeated until its reward, STOP heard. A Sensor is used from one thread (its
handle() runs the requests it answers; it releases the GIL meanwhile).

    import hbirl
    sensor = hbirl.Sensor("corridor", num_symbols=2, num_sources=2, key="runs/x/run.key")
    sensor.wait_for_optimiser()
    sensor.begin_episode()
    sensor.step([1, 0], [[0.8, 0.2], [0.3, 0.7]])    # a step's symbols and their eta
    sensor.end_episode(ends_in_terminal=True)
    sensor.end_run()
    theta = sensor.wait_for_reward()
"""
import math

import numpy as np

from . import _hbirl


def _checked():
    """The package's checks of whole numbers (hbirl/__init__.py: 0.7 is refused, not truncated)."""
    from . import _int, _int_array
    return _int, _int_array


def _seconds(value, name="timeout"):
    """A wait in seconds: a finite number >= 0 (at most a million seconds, ~11 days)."""
    try:
        s = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: must be a number of seconds, got {value!r}") from None
    if not math.isfinite(s) or s < 0:
        raise ValueError(f"{name}: must be a finite number of seconds >= 0, got {value!r}")
    return min(s, 1e6)

__all__ = ["Bus", "Sensor"]


class Bus:
    """The service set's bus: LCM at `url` (LCM's default udpm://239.255.76.67:7667?ttl=0
    when None; ttl=1 reaches other machines), every message signed and checked with `key`
    (a run's key file, services/launch.sh's OUT/run.key) when given -- messages without a
    valid tag for the run reach no handler (docs/RELIABILITY.md). `service` names this
    process in the reports."""

    def __init__(self, url=None, key=None, service="python"):
        self._bus = _hbirl._Bus("" if url is None else str(url), "" if key is None else str(key), str(service))

    def publish(self, channel, message):
        """Publishes `message` -- an hbirl.msg object (its encode()) or bytes -- on `channel`."""
        data = message if isinstance(message, (bytes, bytearray)) else message.encode()
        self._bus.publish(str(channel), bytes(data))

    def subscribe(self, channel, handler, message_type=None):
        """Calls handler(channel, message) for each message on `channel` (a regular
        expression, as LCM's) while handle() runs: the message decoded as `message_type`
        (an hbirl.msg class) when given, else its bytes. Returns the subscription's id."""
        if message_type is None:
            return self._bus.subscribe(str(channel), handler)
        return self._bus.subscribe(str(channel), lambda c, data: handler(c, message_type.decode(data)))

    def unsubscribe(self, subscription):
        self._bus.unsubscribe(subscription)

    def handle(self, timeout=0.1):
        """Delivers waiting messages to their handlers, waiting up to `timeout` seconds for
        the first; returns how many were delivered. A handler's exception is raised here."""
        return self._bus.handle(_seconds(timeout))

    @property
    def authenticated(self):
        """Whether every message is signed and checked with a run key."""
        return self._bus.authenticated


class Sensor:
    """A sensor of the service set for the domain the optimiser knows as `domain` (its
    domain file's "name", else the file's stem): observations of `num_symbols` symbols,
    each with its eta over `num_sources` sources (the subject, then the confounding
    elements); with an end sensor, `num_end_symbols` reports of the terminal state entered.
    Opens its own Bus (url, key) unless `bus` is given. `true_weights`, when known, travel
    with the controlled run's ground truth (the optimiser then reports the ILE).

    Bad input raises ValueError naming the argument; nothing is published for it."""

    def __init__(self, domain, num_symbols, num_sources, *, url=None, key=None, bus=None, num_end_symbols=0,
                 step_seconds=1.0, true_weights=None):
        self.bus = bus if bus is not None else Bus(url, key, service="sensor")
        weights = None if true_weights is None else np.asarray(true_weights, dtype=float)
        self._sensor = _hbirl._Sensor(self.bus._bus, str(domain), int(num_symbols), int(num_sources),
                                      int(num_end_symbols), float(step_seconds), weights)
        self.num_sources = int(num_sources)

    def wait_for_optimiser(self, timeout=10.0):
        """Waits until the optimiser's heartbeat is heard (it then hears the run from its
        first message), at most `timeout` seconds; returns whether it was."""
        return self._sensor.wait_for_optimiser(_seconds(timeout))

    def begin_episode(self, controlled=False):
        """Begins an episode; returns its number. A controlled one (the subject alone, as
        in the paper's controlled run) gives every step's true state and action."""
        return self._sensor.begin_episode(bool(controlled))

    def step(self, symbols=(), eta=None, contexts=None, state=None, action=None):
        """One step of the episode: what was seen -- `symbols` (n,), each with its eta (a
        row of num_sources summing to 1: (n, J)) and, optionally, `contexts` (n,), which
        rule of yours gave each eta (0..65535; learned eta is one distribution per
        context). A step may see nothing. `state` and `action`: the true step, in a
        controlled episode only."""
        as_int, as_ints = _checked()
        symbols = as_ints(symbols, "symbols").reshape(-1)
        eta = np.zeros((0, self.num_sources)) if eta is None else np.asarray(eta, dtype=float)
        if eta.ndim == 1 and symbols.size == 1:
            eta = eta.reshape(1, -1)
        ctx = None if contexts is None else as_ints(contexts, "contexts").reshape(-1)
        self._sensor.step(symbols, eta, ctx, None if state is None else as_int(state, "state"),
                          None if action is None else as_int(action, "action"))

    def end_episode(self, ends_in_terminal=False, end_state=-1, end_symbols=None):
        """Ends the episode: whether its last action entered a terminal state and, of that
        end, the state entered when known (-1: not) and an end sensor's reports."""
        as_int, as_ints = _checked()
        reports = None if end_symbols is None else as_ints(end_symbols, "end_symbols").reshape(-1)
        self._sensor.end_episode(bool(ends_in_terminal), as_int(end_state, "end_state"), reports)

    def end_run(self):
        """Ends the run (END_RUN, stating its episodes): the optimiser learns once it has them all."""
        self._sensor.end_run()

    def handle(self, timeout=0.0):
        """Hears what comes for up to `timeout` seconds: the optimiser's requests for lost
        steps are answered, STOP is noted (stop_requested)."""
        return self._sensor.handle(_seconds(timeout))

    @property
    def stop_requested(self):
        """The optimiser has seen enough (hbirl-optimiser --stop-at-confidence): end the
        run after this episode."""
        return self._sensor.stop_requested

    @property
    def episodes(self):
        """Episodes begun so far."""
        return self._sensor.episodes

    @property
    def frames_resent(self):
        """Steps sent again because the optimiser asked for them."""
        return self._sensor.frames_resent

    def wait_for_reward(self, timeout=600.0):
        """After end_run: answers the optimiser's requests and repeats the end of the run
        until it publishes its reward; returns the learned theta (K,), or None after `timeout`
        seconds."""
        theta = self._sensor.wait_for_reward(_seconds(timeout))
        return None if theta is None else np.asarray(theta)
