#!/usr/bin/env python3
"""Screens variants of the novelty score (issue #43) offline, from neighbour tables, without a build per variant.

Not part of CI, and not runnable on its own: the tables come from a throwaway hook applied to the
presrs tree (`git apply bench/real/novelty_variants.patch`, never merged), which makes
`presrs eval --leave-class-out` append, when `PRESRS_NOVELTY_DUMP=FILE` is set, one JSON line per model
(held-out class, draw seed) and then one per vector:

- `held`: every training/validation vector as the calibration holds it out (its group's fold out of the
  discriminant space and of the neighbours, as `novelty/calibration.rs` does), with, for every class, its
  5 nearest neighbours (distance, index) among the other folds' vectors;
- `test`: every test sample in the model's own discriminant space, the same per-class neighbour lists
  among all training vectors, whether it is of the held-out class, and the classifier's posterior.

Each variant is a score of one such row; its threshold is the 0.95 quantile of the model's `held`
scores (as `NoveltyModel::fit`), its credibility `(k + 1) / (n + 1)` against them, the reported
confidence the posterior capped by it; AUROC per held-out class over the draws pooled, as
`eval --leave-class-out` does. The first variant ("today") reproduces the eval's own figures exactly,
the check that the tables are the model's. Scores that need more than 5 neighbours of a class are
approximate (the LOF-like minimum over neighbours looks at each class's 5 nearest only).

    python3 bench/real/novelty_variants.py TABLE.jsonl [--markdown | --scales | --posterior]

Figures: bench/real/RESULTS.md, "Class-conditional, LOF-like and k-neighbour scores".
"""
import json, sys, statistics, bisect, math
from collections import defaultdict

def load(path):
    models = []
    cur = None
    for line in open(path):
        r = json.loads(line)
        if r['kind'] == 'model':
            cur = {'class': r['class'], 'seed': r['seed'], 'nc': r['n_classes'], 'held': [], 'test': [],
                   'held_post': r.get('held_post')}
            models.append(cur)
        elif r['kind'] == 'held':
            if r['nb'][r['class']]:
                cur['held'].append(r)
        else:
            cur['test'].append(r)
    return models

def quantile(s, q):
    if not s: return float('nan')
    pos = q * (len(s) - 1); b = int(math.floor(pos)); a = min(b + 1, len(s) - 1); w = pos - b
    return s[b] * (1 - w) + s[a] * w

def auroc(pos, neg):
    allv = sorted([(v, 1) for v in pos] + [(v, 0) for v in neg])
    rs = 0.0; i = 0
    while i < len(allv):
        j = i + 1
        while j < len(allv) and allv[j][0] == allv[i][0]: j += 1
        mid = (i + j + 1) / 2
        rs += mid * sum(1 for t in allv[i:j] if t[1])
        i = j
    p, n = len(pos), len(neg)
    return (rs - p * (p + 1) / 2) / (p * n)

def nn(r):  # (dist, idx, class) of the nearest over all classes
    best = (float('inf'), -1, -1)
    for c, l in enumerate(r['nb']):
        if l and l[0][0] < best[0]: best = (l[0][0], l[0][1], c)
    return best

# Each variant: f(model) -> (held_scores, test_scores)
def prep(m):
    cls_of = {}
    r_of = {}
    for h in m['held']:
        cls_of[h['index']] = h['class']
        r_of[h['index']] = nn(h)[0]
    # classes of all training vectors from neighbour lists
    for rows in (m['held'], m['test']):
        for r in rows:
            for c, l in enumerate(r['nb']):
                for d, i in l: cls_of[i] = c
    bycls = defaultdict(list)
    for h in m['held']: bycls[h['class']].append(nn(h)[0])
    glob = statistics.median([nn(h)[0] for h in m['held']])
    m['cls_of'] = cls_of; m['r_of'] = r_of; m['glob'] = glob
    m['scale'] = {c: statistics.median(v) for c, v in bycls.items()}
    # same-class held-out nn
    bys = defaultdict(list)
    for h in m['held']: bys[h['class']].append(h['nb'][h['class']][0][0])
    m['scale_same'] = {c: statistics.median(v) for c, v in bys.items()}
    m['same_sorted'] = {c: sorted(v) for c, v in bys.items()}
    m['scale_mean'] = {c: statistics.mean(v) for c, v in bycls.items()}

def v_base(m, r): return nn(r)[0]
def v_cc(m, r):
    return min(l[0][0] / m['scale'].get(c, m['glob']) for c, l in enumerate(r['nb']) if l)
def v_mondrian(m, r):
    # 1 - the largest class-conditional conformal p-value (Mondrian): for class c, the share of held-out
    # class-c vectors whose distance to the nearest of their own class is at least the sample's to class c.
    best = 0.0
    for c, l in enumerate(r['nb']):
        cal = m['same_sorted'].get(c)
        if l and cal:
            k = len(cal) - bisect.bisect_left(cal, l[0][0])
            best = max(best, (k + 1) / (len(cal) + 1))
    return 1.0 - best
def v_cc_nearest(m, r):
    d, i, c = nn(r); return d / m['scale'].get(c, m['glob'])
def v_cc_same(m, r):
    return min(l[0][0] / m['scale_same'].get(c, m['glob']) for c, l in enumerate(r['nb']) if l)
def v_cc_mean(m, r):
    return min(l[0][0] / m['scale_mean'].get(c, m['glob']) for c, l in enumerate(r['nb']) if l)
def rj(m, i):
    return m['r_of'].get(i, m['scale'].get(m['cls_of'].get(i), m['glob']))
def v_lof1(m, r):
    d, i, c = nn(r); return d / rj(m, i)
def v_lofmin(m, r):
    return min(d / rj(m, i) for l in r['nb'] for d, i in l)
def v_lofk(k):
    def f(m, r):
        best = float('inf')
        for c, l in enumerate(r['nb']):
            if len(l) >= k:
                s = sum(d / rj(m, i) for d, i in l[:k]) / k
                best = min(best, s)
        return best
    return f
def v_kavg(k):
    def f(m, r):
        return min(sum(d for d, _ in l[:k]) / k for l in r['nb'] if len(l) >= k)
    return f
def v_cck(k):
    def f(m, r):
        return min(sum(d for d, _ in l[:k]) / k / m['scale'].get(c, m['glob']) for c, l in enumerate(r['nb']) if len(l) >= k)
    return f

def v_norm(f):
    def g(m, r):
        key = ('thr', f)
        if key not in m:
            m[key] = quantile(sorted(f(m, h) for h in m['held']), 0.5)
        return f(m, r) / m[key]
    return g
VARIANTS = [
    ('nearest training vector (today)', v_base),
    ('1: nearest of each class / that class\'s median held-out nn distance, min over classes', v_cc),
    ('1: nearest vector / its class\'s median held-out nn distance', v_cc_nearest),
    ('1: as the first, scale the median held-out distance to the same class', v_cc_same),
    ('1: as the first, scale the mean held-out nn distance', v_cc_mean),
    ('1: Mondrian conformal: 1 - the largest class-conditional p-value of the nearest of each class', v_mondrian),
    ('2: nearest vector / its own held-out nn distance (LOF-like)', v_lof1),
    ('2: min over neighbours of distance / own held-out nn distance', v_lofmin),
    ('2: LOF-like, mean over the 2 nearest of a class, min over classes', v_lofk(2)),
    ('2: LOF-like, mean over the 3 nearest of a class, min over classes', v_lofk(3)),
    ('3: mean distance to the 2 nearest of a class, min over classes', v_kavg(2)),
    ('3: mean distance to the 3 nearest of a class, min over classes', v_kavg(3)),
    ('1+3: mean of the 2 nearest of a class / class scale, min over classes', v_cck(2)),
    ('1+3: mean of the 3 nearest of a class / class scale, min over classes', v_cck(3)),
    ('check: today / the model\'s median held-out distance (draws pooled fairly)', v_norm(v_base)),
]

def evaluate(models, f):
    per = defaultdict(lambda: {'pos': [], 'neg': [], 'nconf': 0, 'nn': 0, 'krej': 0, 'kn': 0})
    for m in models:
        held = sorted(f(m, h) for h in m['held'])
        thr = quantile(held, 0.95)
        n = len(held)
        P = per[m['class']]
        for t in m['test']:
            s = f(m, t)
            unk = s > thr
            k = n - bisect.bisect_left(held, s)
            cred = (k + 1) / (n + 1)
            conf = min(t['post'], cred)
            if t['novel']:
                P['pos'].append(s); P['nn'] += 1
                P['nconf'] += (not unk) and conf >= 0.9
            else:
                P['neg'].append(s); P['kn'] += 1; P['krej'] += unk
    rows = []
    for c, P in sorted(per.items()):
        rows.append((c, auroc(P['pos'], P['neg']), P['nconf'] / P['nn'], P['krej'] / P['kn']))
    return rows

def calibrated(models):
    """1 - posterior x credibility as a score with a threshold of its own: the 0.95 quantile of the
    held-out training vectors' scores, each with its posterior from a model trained without its fold
    (the hook's `held_post`) and its credibility against the other held-out distances. The confidence is
    the posterior capped by the combined score's own credibility. Beside it, today's distance threshold
    and cap on the same samples."""
    # per (class, method): novel, novel known at >= 0.9, novel unknown, known, known unknown, known at >= 0.9
    per = defaultdict(lambda: [0, 0, 0, 0, 0, 0])
    for m in models:
        held = sorted(nn(h)[0] for h in m['held'])
        n = len(held)
        combined = []
        for h in m['held']:
            post = m['held_post'][h['index']]
            if post is None:
                continue
            k = n - bisect.bisect_left(held, nn(h)[0])
            combined.append(1 - post * (k / n))
        combined.sort()
        thr, thr_today = quantile(combined, 0.95), quantile(held, 0.95)
        for t in m['test']:
            k = n - bisect.bisect_left(held, nn(t)[0])
            cred = (k + 1) / (n + 1)
            c = 1 - t['post'] * cred
            k2 = len(combined) - bisect.bisect_left(combined, c)
            for method, unknown, confidence in [
                    ('today: distance threshold, min(posterior, credibility)', nn(t)[0] > thr_today, min(t['post'], cred)),
                    ('1 - posterior x credibility, its own threshold and credibility', c > thr,
                     min(t['post'], (k2 + 1) / (len(combined) + 1)))]:
                P = per[(m['class'], method)]
                confident = (not unknown) and confidence >= 0.9
                if t['novel']:
                    P[0] += 1; P[1] += confident; P[2] += unknown
                else:
                    P[3] += 1; P[4] += unknown; P[5] += confident
    classes = sorted({c for c, _ in per})
    methods = list(dict.fromkeys(mm for _, mm in per))
    print('| decision | held-out decided known at >= 0.9 | held-out decided unknown, per class | (mean) | '
          'known rejected | known decided at >= 0.9 |')
    print('| --- | --- | --- | --- | --- | --- |')
    for method in methods:
        rows = [per[(c, method)] for c in classes]
        mean = lambda f: sum(f(P) for P in rows) / len(rows)
        print(f'| {method} | {mean(lambda P: 100 * P[1] / P[0]):.1f} % | '
              + ', '.join(f'{c} {100 * P[2] / P[0]:.0f} %' for c, P in zip(classes, rows))
              + f' | {mean(lambda P: 100 * P[2] / P[0]):.1f} % | {mean(lambda P: 100 * P[4] / P[3]):.1f} % | '
              f'{mean(lambda P: 100 * P[5] / P[3]):.1f} % |')
    print()


if __name__ == '__main__':
    models = load(sys.argv[1])
    for m in models: prep(m)
    if '--scales' in sys.argv:
        # Per held-out class, novel and known test samples: the median of (the scale of the class of the
        # nearest training vector) / (the median of all the model's held-out distances).
        out = defaultdict(list)
        for m in models:
            for t in m['test']:
                d, i, c = nn(t)
                out[(m['class'], t['novel'])].append(m['scale'].get(c, m['glob']) / m['glob'])
        for (c, novel), v in sorted(out.items()):
            print(f"{c} {'novel' if novel else 'known'} {statistics.median(v):.3f}")
        sys.exit(0)
    if '--posterior' in sys.argv:
        # AUROC only: the held-out rows have no posterior, so no threshold can be set on these.
        res = defaultdict(lambda: defaultdict(lambda: ([], [])))
        for m in models:
            held = sorted(nn(h)[0] for h in m['held'])
            for t in m['test']:
                k = len(held) - bisect.bisect_left(held, nn(t)[0])
                cred, post = (k + 1) / (len(held) + 1), t['post']
                for name, v in [('1 - max posterior', 1 - post),
                                ('1 - min(posterior, credibility): the confidence reported today', 1 - min(post, cred)),
                                ('1 - posterior x credibility', 1 - post * cred)]:
                    res[m['class']][name][0 if t['novel'] else 1].append(v)
        classes = sorted(res)
        if all(m['held_post'] for m in models):
            calibrated(models)
        print('| score | ' + ' | '.join(classes) + ' | **mean AUROC** |')
        print('| --- ' * (len(classes) + 2) + '|')
        for name in res[classes[0]]:
            a = [auroc(*res[c][name]) for c in classes]
            print(f'| {name} | ' + ' | '.join(f'{x:.3f}' for x in a) + f' | **{sum(a) / len(a):.3f}** |')
        sys.exit(0)
    markdown = '--markdown' in sys.argv
    first = True
    for name, f in VARIANTS:
        rows = evaluate(models, f)
        mean = sum(r[1] for r in rows) / len(rows)
        conf = 100 * sum(r[2] for r in rows) / len(rows)
        rej = 100 * sum(r[3] for r in rows) / len(rows)
        if markdown:
            if first:
                print('| score | ' + ' | '.join(r[0] for r in rows) + ' | **mean AUROC** | held-out known at >= 0.9 | known rejected |')
                print('| --- ' * (len(rows) + 4) + '|')
                first = False
            print(f'| {name} | ' + ' | '.join(f'{r[1]:.3f}' for r in rows) + f' | **{mean:.3f}** | {conf:.1f} % | {rej:.1f} % |')
        else:
            print(f"{name:75s} AUROC {mean:.3f}  held>=.9 {conf:4.1f}%  known rej {rej:4.1f}%  | " + " ".join(f"{r[0]}:{r[1]:.3f}" for r in rows))
