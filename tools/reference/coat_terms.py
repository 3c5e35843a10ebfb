"""The terms of our rough `coated` against Mitsuba 3's `roughplastic` (GGX, nonlinear true).

Both give the base's light as `c t(mu_i) t(mu_o) / (eta^2 (1 - c Ri) pi)`, with `t` the rough
interface's transmission albedo (Mitsuba's `eval_transmittance`: `(1 - F) G1(refracted)` over
the visible normals; ours the same quadrature, tabulated). Until 2026-11-29 ours used
`1 - E(mu)` for `t` (one minus the reflection albedo, counting what masking loses as let
through) and `1 - Ri` for `1 - c Ri`; a random walk through the layer (`sppm-measure coat`)
chose Mitsuba's terms. One difference remains:
- `Ri`: ours is `2 int E_inside(mu) mu dmu` by a fine midpoint rule; Mitsuba's is the plain
  mean of `2 E_inside(mu) mu` over 64 evenly spaced nodes from 0 to 1, endpoints included with
  full weight (about 1.6 % low).
Mitsuba's values are read back from its BSDF: with `nonlinear` true, `f(c)` at two base
colours gives `Ri`; then `f` gives `t(mu)^2`. Ours are recomputed here by quadrature, as
src/materials/coated.rs tabulates them. Run:
    /tmp/venv/bin/python tools/reference/coat_terms.py
"""
import mitsuba as mi
import numpy as np

mi.set_variant('scalar_rgb')
ETA = 1.5


def fresnel(c, eta):
    c = np.clip(c, -1, 1)
    st2 = (1 - c * c) / eta ** 2
    ct = np.sqrt(np.maximum(1 - st2, 0))
    rs = (c - eta * ct) / (c + eta * ct)
    rp = (eta * c - ct) / (eta * c + ct)
    return np.where(st2 >= 1, 1.0, 0.5 * (rs * rs + rp * rp))


def g1(w, a2):
    t2 = (1 - w[..., 2] ** 2) / np.maximum(w[..., 2] ** 2, 1e-12)
    return 2 / (1 + np.sqrt(1 + a2 * t2))


def visible_normals(wo, alpha, u1, u2):
    """Heitz 2018's GGX visible-normal sampling at the points (u1, u2)."""
    vh = np.array([alpha * wo[0], alpha * wo[1], wo[2]])
    vh /= np.linalg.norm(vh)
    lensq = vh[0] ** 2 + vh[1] ** 2
    t1v = np.array([-vh[1], vh[0], 0]) / np.sqrt(lensq) if lensq > 0 else np.array([1.0, 0, 0])
    t2v = np.cross(vh, t1v)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    t1, t2 = r * np.cos(phi), r * np.sin(phi)
    s = 0.5 * (1 + vh[2])
    t2 = (1 - s) * np.sqrt(1 - t1 * t1) + s * t2
    nh = (t1[..., None] * t1v + t2[..., None] * t2v
          + np.sqrt(np.maximum(0, 1 - t1 * t1 - t2 * t2))[..., None] * vh)
    h = np.stack([alpha * nh[..., 0], alpha * nh[..., 1], np.maximum(1e-6, nh[..., 2])], -1)
    return h / np.linalg.norm(h, axis=-1, keepdims=True)


N = 48
_u = (np.arange(N) + 0.5) / N
U1, U2 = (g.ravel() for g in np.meshgrid(_u, _u))


def coat_albedo(mu, alpha, eta):
    """E(mu): mean of F(wo.h) G1(wi) over the visible normals (ours, and Mitsuba's
    `eval_reflectance`)."""
    wo = np.array([np.sqrt(1 - mu * mu), 0, mu])
    h = visible_normals(wo, alpha, U1, U2)
    d = h @ wo
    wi = 2 * d[:, None] * h - wo
    v = fresnel(d, eta) * g1(wi, alpha * alpha)
    v[wi[:, 2] <= 0] = 0
    return v.mean()


def coat_transmission(mu, alpha, eta):
    """t(mu): mean of (1 - F(wo.h)) G1(refracted) over the visible normals (ours, and
    Mitsuba's `eval_transmittance`)."""
    wo = np.array([np.sqrt(1 - mu * mu), 0, mu])
    h = visible_normals(wo, alpha, U1, U2)
    d = h @ wo
    st2 = (1 - d * d) / eta ** 2
    ct = np.sqrt(np.maximum(1 - st2, 0))
    wt = -wo / eta + (d / eta - ct)[:, None] * h
    wt /= np.linalg.norm(wt, axis=-1, keepdims=True)
    v = (1 - fresnel(d, eta)) * g1(-wt, alpha * alpha)
    v[(st2 >= 1) | (wt[:, 2] >= 0)] = 0
    return v.mean()


def mitsuba_terms(alpha):
    def bsdf(c):
        return mi.load_dict({'type': 'roughplastic', 'distribution': 'ggx', 'alpha': alpha,
                             'int_ior': ETA, 'ext_ior': 1.0, 'nonlinear': True,
                             'diffuse_reflectance': {'type': 'rgb', 'value': [c, c, c]}})
    ctx = mi.BSDFContext()
    ctx.component = 1  # the base alone

    def f(b, mu):
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(np.sqrt(1 - mu * mu), 0, mu)
        return b.eval(ctx, si, mi.Vector3f(-np.sqrt(1 - mu * mu), 0, mu))[0]
    one, half = bsdf(1.0), bsdf(0.5)
    ratio = f(one, 1.0) / f(half, 1.0)  # 2 (1 - Ri / 2) / (1 - Ri)
    ri = (ratio - 2) / (ratio - 1)
    return ri, lambda mu: np.sqrt(f(one, mu) * (1 - ri) * np.pi * ETA ** 2 / mu)


def main():
    mus = np.linspace(0.0025, 0.9975, 200)
    for r in [0.2, 0.45, 0.8]:
        a = r * r
        ri_m, t_m = mitsuba_terms(a)
        e_in = np.array([coat_albedo(m, a, 1 / ETA) for m in mus])
        e_out = np.array([coat_albedo(m, a, ETA) for m in mus])
        t_out = np.array([coat_transmission(m, a, ETA) for m in mus])
        ri, exit_share = 2 * np.mean(e_in * mus), 2 * np.mean(t_out * mus)
        div = max(ETA ** 2 * (1 - ri), exit_share)
        print(f'roughness {r}: Ri ours {ri:.4f}, Mitsuba {ri_m:.4f}; divisor ours {div:.4f}, '
              f'Mitsuba {ETA ** 2 * (1 - ri_m):.4f}')
        for mu in [1.0, 0.7, 0.4, 0.15]:
            t, tm = coat_transmission(mu, a, ETA), t_m(mu)
            print(f'  cos {mu}: t ours {t:.4f}, Mitsuba {tm:.4f} (Mitsuba / ours {tm / t:.4f})')
        tt = np.array([t_m(m) for m in mus[::4]])
        ours = coat_transmission(1.0, a, ETA) * exit_share / div
        theirs = t_m(1.0) * 2 * np.mean(tt * mus[::4]) / (ETA ** 2 * (1 - ri_m))
        print(f'  white base seen head-on, base part of the albedo: ours {ours:.4f}, '
              f'Mitsuba {theirs:.4f}')


if __name__ == '__main__':
    main()
