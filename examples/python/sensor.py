#!/usr/bin/env python3
"""A complete sensor for examples/corridor.json, written with nothing but `import hbirl`
(docs/python.md "Python sensors"). A camera at the end of a 4-cell corridor watches a person
walk to the exit (cell 3); now and then a passer-by is in view too. Each step it reports
what its detector saw -- symbol 0 "a blob far left", 1 "a blob near the exit" -- with eta,
how likely each blob is the person or the passer-by, and which of its two rules gave that
eta (the contexts: 0 "tracked person", 1 "unknown blob").

Run it against the service set:

    services/launch.sh --domain examples/corridor.json --no-sim --sensor-key \\
        --sensor "python3 examples/python/sensor.py"

(launch.sh appends --url and --key), or against an hbirl-optimiser you started with
--domain examples/corridor.json. --save FILE also writes what it published as a problem
file: `hbirl learn --problem FILE` then learns the optimiser's theta, bit for bit.
"""
import argparse
import json
import os
import sys

import numpy as np

import hbirl

HERE = os.path.dirname(os.path.abspath(__file__))
EXIT = 3  # the corridor's terminal cell


def walk(rng):
    """One walk to the exit: the (cell, action) steps; the expert always goes right (1),
    a move succeeds 8 times in 10."""
    cell, steps = int(rng.random() < 0.5), []
    while cell != EXIT:
        steps.append((cell, 1))
        if rng.random() < 0.8:
            cell += 1
    return steps


def seen(rng, cell, passers_by):
    """What the camera reports of a step: (symbols, eta, contexts)."""
    symbols, eta, contexts = [], [], []
    if rng.random() < 0.8:  # the person, tracked; the detector errs 1 time in 5
        symbols.append(int((cell == 2) != (rng.random() < 0.2)))
        eta.append([0.8, 0.2])
        contexts.append(0)
    if passers_by and rng.random() < 0.3:  # a passer-by, mostly far left
        symbols.append(int(rng.random() < 0.25))
        eta.append([0.3, 0.7])
        contexts.append(1)
    return symbols, eta, contexts


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--url", help="LCM URL (default: LCM's)")
    parser.add_argument("--key", help="the run's key file (services/launch.sh writes OUT/run.key)")
    parser.add_argument("--episodes", type=int, default=30, help="walks to publish (default 30)")
    parser.add_argument("--controlled", type=int, default=0,
                        help="walks of a controlled run first: the person alone, true steps known (default 0)")
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--domain", default=os.path.join(HERE, "..", "corridor.json"),
                        help="the domain file the optimiser learns on (for --save)")
    parser.add_argument("--save", help="also write what was published as a problem file")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds to wait for the reward")
    args = parser.parse_args()

    rng = np.random.default_rng(args.seed)
    sensor = hbirl.Sensor("corridor", num_symbols=2, num_sources=2, url=args.url, key=args.key)
    if not sensor.wait_for_optimiser(10.0):
        print("sensor.py: no optimiser heard in 10 s; publishing anyway", file=sys.stderr)
    published = []
    for n in range(args.controlled + args.episodes):
        controlled = n < args.controlled
        sensor.begin_episode(controlled=controlled)
        steps = []
        for cell, action in walk(rng):
            symbols, eta, contexts = seen(rng, cell, passers_by=not controlled)
            if controlled:  # the person alone: every blob is theirs
                eta = [[1.0, 0.0] for _ in symbols]
            sensor.step(symbols, eta, contexts, state=cell if controlled else None,
                        action=action if controlled else None)
            steps.append((cell, action, symbols, eta, contexts))
        sensor.end_episode(ends_in_terminal=True)
        published.append((controlled, steps))
        if sensor.stop_requested:  # the optimiser has seen enough
            break
    sensor.end_run()
    print(f"sensor.py: {len(published)} walks published", file=sys.stderr)
    if args.save:
        save(args.domain, published, args.save)
    theta = sensor.wait_for_reward(args.timeout)
    if theta is None:
        print("sensor.py: no reward within the timeout", file=sys.stderr)
        return 1
    print(f"sensor.py: the optimiser learned theta {theta.tolist()}; {sensor.frames_resent} steps sent again",
          file=sys.stderr)
    return 0


def save(domain_file, published, path):
    """What was published as a problem file (docs/files.md "Problem files"): the domain's MDP
    and observation model, the walks' observations as [symbol, eta, context]."""
    with open(domain_file, encoding="utf-8") as f:
        problem = json.load(f)
    problem["name"] = "corridor"
    problem["demonstration"] = []
    for controlled, steps in published:
        walk_ = {"steps": [{"observations": [[w, e, c] for w, e, c in zip(symbols, eta, contexts)]}
                           for _, _, symbols, eta, contexts in steps],
                 "ends_in_terminal": True}
        if controlled:
            walk_["controlled"] = True
            walk_["truth"] = [[cell, action] for cell, action, _, _, _ in steps]
        problem["demonstration"].append(walk_)
    with open(path, "w", encoding="utf-8") as f:
        json.dump(problem, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
