"""Directional albedo of Mitsuba 3's `roughplastic` (GGX, nonlinear false), the other model
`sppm-measure coat` compares against its random walk through the layer.

Its specular lobe is the product's (`E(mu)`, computed here as tools/reference/coat_terms.py
does); its base part is `c t(mu) 2 int t(mu') mu' dmu' / (eta^2 (1 - Ri))` with Mitsuba's own
transmittance `t` and internal reflectance `Ri`, read back from its BSDF by coat_terms.py.
Prints Markdown rows (roughness, base c, cos, albedo). Run from the repository root:
    .venv/bin/python tools/measure/roughplastic_albedo.py
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'reference'))
import coat_terms as ct  # noqa: E402


def main():
    mus = np.linspace(0.0025, 0.9975, 200)
    print('| roughness | base c | cos | roughplastic |\n|---|---|---|---|')
    for r in [0.2, 0.45, 0.8]:
        a = r * r
        ri, t = ct.mitsuba_terms(a)
        tt = np.array([t(m) for m in mus[::4]])
        exit_share = 2 * np.mean(tt * mus[::4])
        for c in [1.0, 0.7, 0.15]:
            for mu in [1.0, 0.7, 0.4, 0.15]:
                spec = ct.coat_albedo(mu, a, ct.ETA)
                base = c * t(mu) * exit_share / (ct.ETA ** 2 * (1 - ri))
                print(f'| {r} | {c} | {mu} | {spec + base:.4f} |')


if __name__ == '__main__':
    main()
