"""Python sensors (docs/python.md "Python sensors"): hbirl.msg, hbirl.Bus and hbirl.Sensor.
Over LCM's in-process provider (memq://) here, so no packet leaves the process; over real
LCM against the optimiser, signed: the multi-process test services.python_sensor."""
import os
import subprocess

import numpy as np
import pytest

import hbirl

CLI = os.environ.get("HBIRL_CLI")


def listen(bus):
    """Everything the bus carries, decoded, in order."""
    heard = []
    types = {"EPISODE": hbirl.msg.episode_marker_t, "OBSERVATIONS": hbirl.msg.observations_t,
             "GROUND_TRUTH": hbirl.msg.ground_truth_t}
    for channel, kind in types.items():
        bus.subscribe(channel, lambda c, m: heard.append((c, m)), kind)
    return heard


def drain(bus):
    while bus.handle(0.0) > 0:
        pass


def test_messages_round_trip():
    o = hbirl.msg.observations_t()
    o.episode, o.step, o.num_symbols, o.num_sources, o.n = 3, 4, 2, 2, 1
    o.symbol, o.eta = [1], [[0.25, 0.75]]
    back = hbirl.msg.observations_t.decode(o.encode())
    assert (back.episode, back.step, list(back.symbol), [list(r) for r in back.eta]) == (3, 4, [1], [[0.25, 0.75]])


def test_a_sensor_publishes_the_protocol():
    bus = hbirl.Bus("memq://")
    heard = listen(bus)
    sensor = hbirl.Sensor("corridor", num_symbols=2, num_sources=2, bus=bus, true_weights=[1.0, 0.0])
    assert sensor.begin_episode(controlled=True) == 0
    sensor.step([1], [[1.0, 0.0]], state=2, action=1)
    sensor.end_episode(ends_in_terminal=True)
    assert sensor.begin_episode() == 1
    sensor.step([1, 0], [[0.8, 0.2], [0.3, 0.7]], contexts=[0, 1])
    sensor.step()  # a step that saw nothing
    sensor.end_episode(ends_in_terminal=True)
    sensor.end_run()
    drain(bus)
    kinds = [(c, getattr(m, "kind", None), m.episode) for c, m in heard]
    B, S, E, R = (hbirl.msg.episode_marker_t.BEGIN_EPISODE, hbirl.msg.episode_marker_t.BEGIN_STEP,
                  hbirl.msg.episode_marker_t.END_EPISODE, hbirl.msg.episode_marker_t.END_RUN)
    assert kinds == [("EPISODE", B, 0), ("EPISODE", S, 0), ("GROUND_TRUTH", None, 0), ("OBSERVATIONS", None, 0),
                     ("EPISODE", E, 0), ("EPISODE", B, 1), ("EPISODE", S, 1), ("OBSERVATIONS", None, 1),
                     ("EPISODE", S, 1), ("OBSERVATIONS", None, 1), ("EPISODE", E, 1), ("EPISODE", R, 0)]
    markers = [m for c, m in heard if c == "EPISODE"]
    assert all(m.domain == "corridor" for m in markers)
    assert [m.controlled for m in markers if m.kind == B] == [True, False]
    ends = [m for m in markers if m.kind == E]
    assert [(m.num_steps, m.ends_in_terminal) for m in ends] == [(1, True), (2, True)]
    assert markers[-1].num_steps == 2  # END_RUN states the run's episodes
    truth = [m for c, m in heard if c == "GROUND_TRUTH"][0]
    assert (truth.state, truth.action, list(truth.true_weights)) == (2, 1, [1.0, 0.0])
    seen = [m for c, m in heard if c == "OBSERVATIONS"]
    assert [list(m.symbol) for m in seen] == [[1], [1, 0], []]
    assert [list(r) for r in seen[1].eta] == [[0.8, 0.2], [0.3, 0.7]]
    assert list(seen[1].context) == [0, 1] and seen[1].num_context == 2 and seen[2].num_context == 0
    assert [m.step for m in seen] == [0, 0, 1]
    assert seen[1].utime < seen[2].utime  # sim time: one second a step, episodes back to back


@pytest.mark.parametrize("call, field", [
    (lambda s: s.step([0], [[1.0, 0.0]]), "step: outside an episode"),
    (lambda s: s.end_episode(), "end_episode: outside an episode"),
    (lambda s: s.end_run(), "end_run: the run has no episode"),
    (lambda s: (s.begin_episode(), s.begin_episode()), "begin_episode: episode 0 is under way"),
    (lambda s: (s.begin_episode(), s.step([2], [[1.0, 0.0]])), "symbols[0]: 2 is not in [0, 2)"),
    (lambda s: (s.begin_episode(), s.step([0], [[0.5, 0.6]])), "eta[0]: sums to"),
    (lambda s: (s.begin_episode(), s.step([0], [[-0.5, 1.5]])), "eta[0]: entry 0"),
    (lambda s: (s.begin_episode(), s.step([0, 1], [[1.0, 0.0]])), "eta: must be 2 x 2"),
    (lambda s: (s.begin_episode(), s.step([0], [[1.0, 0.0]], contexts=[0, 1])), "contexts: must give one per symbol"),
    (lambda s: (s.begin_episode(), s.step([0], [[1.0, 0.0]], contexts=[70000])), "contexts[0]: is not in"),
    (lambda s: (s.begin_episode(), s.step([0], [[1.0, 0.0]], contexts=[0]), s.step([0], [[1.0, 0.0]])),
     "contexts: missing, where the demonstrations' observations before had them"),
    (lambda s: (s.begin_episode(), s.step([0], [[1.0, 0.0]]), s.step(), s.end_episode(), s.begin_episode(),
                s.step([0], [[1.0, 0.0]], contexts=[1])),
     "contexts: given, where the demonstrations' observations before had none"),
    (lambda s: (s.begin_episode(), s.step([0.7], [[1.0, 0.0]])), "symbols: must be whole numbers"),
    (lambda s: (s.begin_episode(controlled=True), s.step([0], [[1.0, 0.0]], state=1.5, action=0)),
     "state: must be a whole number"),
    (lambda s: (s.begin_episode(), s.step(), s.end_episode(True, end_state=0.5)), "end_state: must be a whole"),
    (lambda s: s.handle(-1), "timeout: must be a finite number of seconds >= 0"),
    (lambda s: s.wait_for_optimiser(float("nan")), "timeout: must be a finite"),
    (lambda s: (s.begin_episode(), s.step(), s.end_episode(), s.end_run(), s.wait_for_reward(float("inf"))),
     "timeout: must be a finite"),
    (lambda s: (s.begin_episode(controlled=True), s.step([0], [[1.0, 0.0]])), "state: a controlled episode"),
    (lambda s: (s.begin_episode(), s.step([0], [[1.0, 0.0]], state=1, action=1)), "state: a demonstration"),
    (lambda s: (s.begin_episode(controlled=True), s.step([0], [[1.0, 0.0]], state=1)), "action: give the true"),
    (lambda s: (s.begin_episode(), s.end_episode()), "end_episode: an episode needs at least one step"),
    (lambda s: (s.begin_episode(), s.step(), s.end_episode(end_state=3)), "end_state: only an episode that ends"),
    (lambda s: (s.begin_episode(), s.step(), s.end_episode(True, end_symbols=[0])), "end_symbols[0]: 0 is not in"),
    (lambda s: (s.begin_episode(), s.step(), s.end_episode(), s.end_run(), s.begin_episode()),
     "begin_episode: the run has ended"),
    (lambda s: s.wait_for_reward(0.1), "wait_for_reward: the run has not ended"),
])
def test_bad_input_is_refused_naming_the_argument(call, field):
    bus = hbirl.Bus("memq://")
    heard = listen(bus)
    sensor = hbirl.Sensor("corridor", num_symbols=2, num_sources=2, bus=bus)
    steps = []
    step = sensor.step
    sensor.step = lambda *a, **k: (step(*a, **k), steps.append(1))  # counts the steps accepted
    with pytest.raises(ValueError, match="^" + field.replace("[", r"\[").replace("(", r"\(").replace(")", r"\)")):
        call(sensor)
    drain(bus)
    assert sum(c == "OBSERVATIONS" for c, _ in heard) == len(steps)  # nothing published for bad input


@pytest.mark.parametrize("kwargs, field", [
    (dict(domain="a b"), "domain: 'a b'"),
    (dict(num_symbols=0), "num_symbols: must be in"),
    (dict(num_sources=0), "num_sources: must be at least 1"),
    (dict(step_seconds=0.0), "step_seconds: must be a positive"),
    (dict(true_weights=[np.nan]), "true_weights: must be finite"),
])
def test_a_sensor_no_optimiser_could_take_is_refused(kwargs, field):
    args = dict(domain="corridor", num_symbols=2, num_sources=2)
    args.update(kwargs)
    with pytest.raises(ValueError, match="^" + field):
        hbirl.Sensor(args.pop("domain"), args.pop("num_symbols"), args.pop("num_sources"), bus=hbirl.Bus("memq://"),
                     **args)


def test_a_handler_that_raises_is_raised_from_handle():
    bus = hbirl.Bus("memq://")

    def handler(channel, data):
        raise RuntimeError("the handler's own error")

    bus.subscribe("X", handler)
    bus.publish("X", b"anything")
    with pytest.raises(RuntimeError, match="the handler's own error"):
        bus.handle(0.1)
    assert bus.handle(0.0) == 0  # and the bus goes on


def test_a_handler_may_not_unsubscribe_while_handled():
    bus = hbirl.Bus("memq://")
    ids = []

    def handler(channel, data):
        bus.unsubscribe(ids[0])

    ids.append(bus.subscribe("X", handler))
    bus.publish("X", b"anything")
    with pytest.raises(ValueError, match="^unsubscribe: not from inside a handler"):
        bus.handle(0.1)
    bus.unsubscribe(ids[0])  # afterwards, fine
    bus.publish("X", b"anything")
    assert bus.handle(0.05) == 0


def test_a_signed_bus(tmp_path):
    if not CLI:
        pytest.skip("HBIRL_CLI (the hbirl command) not set: run through ctest")
    key = tmp_path / "run.key"
    subprocess.run([CLI, "keygen", str(key), "--run"], check=True, capture_output=True)
    bus = hbirl.Bus("memq://", key=str(key))
    assert bus.authenticated and not hbirl.Bus("memq://").authenticated
    heard = listen(bus)
    sensor = hbirl.Sensor("corridor", 2, 2, bus=bus)
    sensor.begin_episode()
    sensor.step([1], [[0.8, 0.2]])
    drain(bus)
    assert [c for c, _ in heard] == ["EPISODE", "EPISODE", "OBSERVATIONS"]  # signed, checked, delivered
    with pytest.raises(ValueError, match="^key"):
        hbirl.Bus("memq://", key=str(tmp_path / "missing.key"))
    many = tmp_path / "many.key"  # a key for many runs names none: a sensor signs for one run
    subprocess.run([CLI, "keygen", str(many)], check=True, capture_output=True)
    with pytest.raises(ValueError, match="^key"):
        hbirl.Bus("memq://", key=str(many))
