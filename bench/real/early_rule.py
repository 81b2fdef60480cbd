#!/usr/bin/env python3
"""Screens rules for `auto`'s early decisions (issue #43) offline, from held-out outcomes, without a build
per rule.

Not part of CI, and not runnable on its own: the outcomes come from a throwaway hook applied to the presrs
tree (`git apply bench/real/early_rule.patch`, never merged), which makes `presrs eval --decide-at auto`
append, when `PRESRS_DUMP_EARLY=FILE` is set, two JSON lines per fold: `val`, the held-out stances of the
fold's inner folds (what the rule learns from), then `test`, the fold's test stances as its model decided
them. Each stance is `[class, length, [[class, confidence] or null per point], [whole class, confidence]]`.

Each rule is learned on a fold's `val` stances and scored on its `test` stances, as `eval` does; `today`
re-implements `learn_threshold` (crates/presrs-core/src/pipeline/early.rs) and reproduces the eval's own
figures, the check that the outcomes are the model's. Printed per rule: accuracy and mean decision over
the median test stance for the whole run and for each repeat (`--folds-per-repeat`: 2 on jiku-walk's
leave one walker out, 3 on the simulator's leave one condition out). Plain Python, no packages.
"""

from __future__ import annotations

import argparse
import json
import math
import signal

TOLERANCE, BOUND_Z, EARLINESS = 0.02, 1.0, 0.5
NEVER = 1.0 + math.sqrt(2.220446049250313e-16)


def load(path):
    lines = [json.loads(line) for line in open(path)]
    folds = []
    for val, test in zip(lines[0::2], lines[1::2]):
        assert (val["kind"], test["kind"]) == ("val", "test"), "lines come in val, test pairs"
        folds.append((val["frames"], val["stances"], test["stances"]))
    return folds


def decide(stance, frames, threshold, deadline):
    """(class, confidence, frame, decided early) of one stance, as `HeldOutStance::decide`."""
    _, length, points, whole = stance
    for k, outcome in zip(frames, points):
        if outcome is not None and (outcome[1] >= threshold or deadline == k):
            return outcome[0], outcome[1], k, True
    return whole[0], whole[1], length, False


def wilson_lower(right, n, z):
    if n == 0:
        return 0.0
    p, z2 = right / n, z * z
    centre = p + z2 / (2 * n)
    spread = z * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n))
    return max((centre - spread) / (1 + z2 / n), 0.0)


def safe(stances, frames, threshold, deadline):
    early = right = whole_right = 0
    for stance in stances:
        cls, _, _, is_early = decide(stance, frames, threshold, deadline)
        if is_early:
            early += 1
            right += cls == stance[0]
            whole_right += stance[3][0] == stance[0]
    if early == 0:
        return True
    return wilson_lower(right, early, BOUND_Z) >= whole_right / early - TOLERANCE - 1e-12


def mean_frame(stances, frames, threshold, deadline):
    return sum(decide(s, frames, threshold, deadline)[2] for s in stances) / len(stances)


def mean_confidence(stances, frames, threshold, deadline):
    return sum(decide(s, frames, threshold, deadline)[1] for s in stances) / len(stances)


def median_length(stances):
    lengths = sorted(s[1] for s in stances)
    return lengths[(len(lengths) - 1) // 2]


def thresholds(stances):
    seen = sorted({o[1] for s in stances for o in s[2] if o is not None})
    return seen + [NEVER]


def rule_today(stances, frames):
    """The threshold first (as if the stances it leaves waited for lift-off), then the latest deadline."""
    due = EARLINESS * median_length(stances)
    safe_ones = [t for t in thresholds(stances) if safe(stances, frames, t, None)]
    in_time = [t for t in safe_ones if mean_frame(stances, frames, t, None) <= due]
    threshold = in_time[-1] if in_time else (safe_ones[0] if safe_ones else NEVER)
    deadlines = [k for k in frames if safe(stances, frames, threshold, k)]
    in_time = [k for k in deadlines if mean_frame(stances, frames, threshold, k) <= due]
    deadline = in_time[-1] if in_time else (deadlines[0] if deadlines else None)
    return threshold, deadline


def highest_in_time(stances, frames, deadline, due):
    ok = [t for t in thresholds(stances)
          if mean_frame(stances, frames, t, deadline) <= due and safe(stances, frames, t, deadline)]
    return ok[-1] if ok else None


def joint_rules(stances, frames, deadlines):
    due = EARLINESS * median_length(stances)
    rules = []
    for deadline in deadlines:
        threshold = highest_in_time(stances, frames, deadline, due)
        if threshold is not None:
            rules.append((threshold, deadline))
    return rules


def rule_most_confident(stances, frames):
    """For no deadline and each point, the highest safe threshold in time; the most confident of those."""
    rules = joint_rules(stances, frames, [None] + list(frames))
    if not rules:
        return rule_today(stances, frames)
    return max(rules, key=lambda r: (mean_confidence(stances, frames, *r), -mean_frame(stances, frames, *r)))


def rule_highest_threshold(stances, frames):
    """The same rules, the highest threshold (ties: the latest deadline)."""
    rules = joint_rules(stances, frames, [None] + list(frames))
    if not rules:
        return rule_today(stances, frames)
    return max(rules, key=lambda r: (r[0], -1 if r[1] is None else r[1]))


def rule_most_accurate(stances, frames):
    """The same rules, the most accurate in validation (ties: the highest threshold)."""
    rules = joint_rules(stances, frames, [None] + list(frames))
    if not rules:
        return rule_today(stances, frames)

    def accuracy(rule):
        return sum(decide(s, frames, *rule)[0] == s[0] for s in stances) / len(stances)

    return max(rules, key=lambda r: (accuracy(r), r[0]))


def rule_most_confident_of_all(stances, frames):
    """Every safe threshold in time with each deadline (not only the highest): the most confident."""
    due = EARLINESS * median_length(stances)
    best = None
    for deadline in [None] + list(frames):
        for t in thresholds(stances):
            if mean_frame(stances, frames, t, deadline) <= due and safe(stances, frames, t, deadline):
                key = (mean_confidence(stances, frames, t, deadline), t)
                if best is None or key > best[0]:
                    best = (key, (t, deadline))
    return best[1] if best else rule_today(stances, frames)


def rule_deadlines_only(stances, frames):
    rules = joint_rules(stances, frames, list(frames))
    if not rules:
        return rule_most_confident(stances, frames)
    return max(rules, key=lambda r: (mean_confidence(stances, frames, *r), -mean_frame(stances, frames, *r)))


RULES = {
    "today": rule_today,
    "most_confident": rule_most_confident,
    "highest_threshold": rule_highest_threshold,
    "most_accurate": rule_most_accurate,
    "deadlines_only": rule_deadlines_only,
    "most_confident_of_all": rule_most_confident_of_all,
}


def score(folds, rules):
    """Accuracy and mean decision over the median test stance of `folds` decided by `rules`."""
    tests = [test for _, _, test in folds]
    median = median_length([s for test in tests for s in test])
    right = frames_sum = n = 0
    for (frames, _, test), (threshold, deadline) in zip(folds, rules):
        for stance in test:
            cls, _, frame, _ = decide(stance, frames, threshold, deadline)
            right += cls == stance[0]
            frames_sum += frame
            n += 1
    return right / n, frames_sum / n / median


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("outcomes", nargs="+", help="files the hook wrote")
    parser.add_argument("--folds-per-repeat", type=int, default=2)
    args = parser.parse_args()
    for path in args.outcomes:
        folds = load(path)
        print(path)
        for name, learn in RULES.items():
            rules = [learn(val, frames) for frames, val, _ in folds]
            accuracy, share = score(folds, rules)
            per = args.folds_per_repeat
            repeats = [score(folds[i:i + per], rules[i:i + per]) for i in range(0, len(folds), per)]
            shown = ", ".join(f"{a * 100:.1f} % at {m:.2f}" for a, m in repeats)
            print(f"  {name:22} {accuracy * 100:6.2f} % at {share:.3f} of the median stance; per repeat {shown}")


if __name__ == "__main__":
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # a closed pipe (| head) ends quietly
    main()
