#!/usr/bin/env python3
"""Counts of MCMT_X_SURROUND_TRACE (surround probe, 2026-12-07-surround-switches.patch).

A line per model refinement: model-only round, settled, model passes, side fits at the 12-iteration cap,
then per side one token per model pass, `CTXn:m,` (C the surround choice: t two-level, f faint (one level
this pass only), s one level kept, x no warm fit; T: - / T the model turned the line / C no crossing;
X: c a second-step cut, - none; n: the rays CollectSideRays kept; m: the side's move, px), then the
largest corner move per model pass. Prints, for settled and unsettled refinements, how many had a side
whose choice, turn, cut or ray count changed between model passes, and a fit at the cap."""
import collections
import sys

for path in sys.argv[1:]:
    n = collections.Counter()
    kinds = collections.Counter()
    for line in open(path):
        w = line.split()
        settled, passes, caps = int(w[1]), int(w[2]), int(w[3])
        changed = collections.Counter()
        for side in w[4:8]:
            toks = [t for t in side.split(',') if t]
            parts = {'choice': [t[0] for t in toks], 'turn': [t[1] for t in toks],
                     'cut': [t[2] for t in toks], 'rays': [t[3:].split(':')[0] for t in toks]}
            for name, seq in parts.items():
                changed[name] += len(set(seq)) > 1
            for a, b in zip(parts['choice'], parts['choice'][1:]):
                if a != b:
                    kinds[('settled ' if settled else 'unsettled ') + a + b] += 1
        key = 'settled' if settled else 'unsettled'
        n[key] += 1
        n[key + ' passes'] += passes
        n[key + ' capped'] += caps > 0
        for name in ('choice', 'turn', 'cut', 'rays'):
            n[key + ' ' + name] += changed[name] > 0
        n[key + ' none'] += sum(changed.values()) == 0
        n[key + ' none, no cap'] += sum(changed.values()) == 0 and caps == 0
    tot = n['settled'] + n['unsettled']
    print(path, 'refinements', tot, 'unsettled %.1f %%' % (100.0 * n['unsettled'] / tot),
          'model passes', n['settled passes'] + n['unsettled passes'])
    for key in ('settled', 'unsettled'):
        k = max(1, n[key])
        print('  %s %d: passes %.2f; a side fit at the cap %.0f %%; a side changed its choice %.0f %%, turn %.0f %%,'
              ' cut %.0f %%, rays %.0f %%; none of these %.0f %% (and no cap %.0f %%)' %
              (key, n[key], n[key + ' passes'] / k, 100.0 * n[key + ' capped'] / k, 100.0 * n[key + ' choice'] / k,
               100.0 * n[key + ' turn'] / k, 100.0 * n[key + ' cut'] / k, 100.0 * n[key + ' rays'] / k,
               100.0 * n[key + ' none'] / k, 100.0 * n[key + ' none, no cap'] / k))
    print('  choice switches:', ', '.join('%s %d' % kv for kv in kinds.most_common(12)))
