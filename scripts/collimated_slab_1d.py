#!/usr/bin/env python3
"""The issue-19 box as a 1D slab: transport against the diffusion models.

A collimated beam enters a slab (10 mm; mu_a 0.01/mm, mu_s 1/mm, isotropic
scattering, eta 1.3, Fresnel boundaries with total internal reflection on
both faces) at normal incidence. Prints the mean total fluence 2-7 mm deep
(the depth range of CollimatedSource.GapToMonteCarloOnTheIssuesBox) of

  - transport: discrete ordinates (double-Gauss S_N, step characteristics,
    source iteration) with the exact collimated / diffuse split;
  - the P1 diffusion models: "surface" (the beam as boundary irradiance q)
    and "extended" (the volume source mu_s' E_c), each with the Robin
    coefficients of the fit (A = (1 + Fdr)/(1 - Fdr), Fdr Groenhuis/Jensen)
    and of the Fresnel moments (A = (1 + R_J)/(1 - R_phi), Fdr = R_phi),

as ratios to transport. Documentation/DiffuseOptics.md quotes the output.
Usage: collimated_slab_1d.py [angles per hemisphere, default 32] [dz mm, default 0.002]
(about 20 s; 16 0.01 gives the same ratios to 0.5 %).
"""
import sys

import numpy as np
import scipy.linalg as sl
import scipy.signal as sg

ETA, MUA, MUS, THICKNESS = 1.3, 0.01, 1.0, 10.0
MUT = MUA + MUS
T0 = 1.0 - ((ETA - 1.0) / (ETA + 1.0)) ** 2  # normal-incidence transmittance


def reflectance_outside(c, n):
    """Fresnel R for the outside cosine c (= internal R by reciprocity)."""
    ct = np.sqrt(1.0 - (1.0 - c * c) / n ** 2)
    rs = (c - n * ct) / (c + n * ct)
    rp = (n * c - ct) / (n * c + ct)
    return 0.5 * (rs * rs + rp * rp)


def reflectance_inside(mu, n):
    """Fresnel R for the internal cosine mu (1 beyond the critical angle)."""
    mu = np.asarray(mu, float)
    s2 = n * n * (1.0 - mu * mu)
    r = np.ones_like(mu)
    ok = s2 < 1.0
    r[ok] = reflectance_outside(np.sqrt(1.0 - s2[ok]), n)
    return r


def moments(n):
    """R_phi = 2 int R mu dmu, R_J = 3 int R mu^2 dmu (over the outside cosine)."""
    x, w = np.polynomial.legendre.leggauss(64)
    c, w = 0.5 * (x + 1.0), 0.5 * w
    mu_c2 = 1.0 - 1.0 / n ** 2
    mu = np.sqrt(1.0 - (1.0 - c * c) / n ** 2)
    r = reflectance_outside(c, n)
    return (mu_c2 + 2.0 * np.sum(w * r * c) / n ** 2,
            mu_c2 ** 1.5 + 3.0 * np.sum(w * r * c * mu) / n ** 2)


def transport(angles, dz, tol=1e-11):
    nz = int(round(THICKNESS / dz))
    z = np.linspace(0.0, THICKNESS, nz + 1)
    x, w = np.polynomial.legendre.leggauss(angles)
    mu, w = 0.5 * (x + 1.0), 0.5 * w
    collimated = T0 * (np.exp(-MUT * z[:-1]) - np.exp(-MUT * z[1:])) / (MUT * dz)  # cell means
    r = reflectance_inside(mu, ETA)
    a = np.exp(-MUT * dz / mu)
    phi = np.zeros(nz)
    top_in, bottom_in = np.zeros(angles), np.zeros(angles)
    for _ in range(100000):
        src = (MUS * phi + MUS * collimated) / (4.0 * np.pi) / MUT
        new = np.zeros(nz)
        down_out, up_out = np.zeros(angles), np.zeros(angles)
        for j in range(angles):
            tau = MUT * dz / mu[j]
            b = (1.0 - a[j]) * src
            down = sg.lfilter([1.0], [1.0, -a[j]], np.concatenate(([top_in[j]], b)))
            new += 2.0 * np.pi * w[j] * (src + (down[:-1] - src) * (1.0 - a[j]) / tau)
            down_out[j] = down[-1]
            up = sg.lfilter([1.0], [1.0, -a[j]], np.concatenate(([bottom_in[j]], b[::-1])))
            new += 2.0 * np.pi * w[j] * (src[::-1] + (up[:-1] - src[::-1]) * (1.0 - a[j]) / tau)[::-1]
            up_out[j] = up[-1]
        bottom_in, top_in = r * down_out, r * up_out
        change = np.max(np.abs(new - phi)) / np.max(new)
        phi = new
        if change < tol:
            break
    return 0.5 * (z[1:] + z[:-1]), phi + collimated


def diffusion(model, a, fdr, dz=0.002):
    """-D phi'' + mu_a phi = S, phi + 2 A D dphi/dn = 4 q / (1 - Fdr) on both faces."""
    d = 1.0 / (3.0 * MUT)
    nz = int(round(THICKNESS / dz))
    z = np.linspace(0.0, THICKNESS, nz + 1)
    ec = T0 * np.exp(-MUT * z)
    rhs = MUS * ec if model == "extended" else np.zeros(nz + 1)
    c0 = 4.0 * T0 / (1.0 - fdr) if model == "surface" else 0.0
    band = np.zeros((3, nz + 1))
    band[1] = 2.0 * d / dz ** 2 + MUA
    band[1, [0, -1]] += 1.0 / (a * dz)  # ghost points of the Robin condition
    band[0, 1:] = band[2, :-1] = -d / dz ** 2
    band[0, 1] = band[2, -2] = -2.0 * d / dz ** 2
    rhs = rhs.copy()
    rhs[0] += c0 / (a * dz)
    phi = sl.solve_banded((1, 1), band, rhs)
    return z, phi + (ec if model == "extended" else 0.0)


def main():
    angles = int(sys.argv[1]) if len(sys.argv) > 1 else 32
    dz = float(sys.argv[2]) if len(sys.argv) > 2 else 0.002
    r_phi, r_j = moments(ETA)
    fdr = -1.440 / ETA ** 2 + 0.710 / ETA + 0.668 + 0.0636 * ETA
    rules = {"fit": ((1 + fdr) / (1 - fdr), fdr), "moments": ((1 + r_j) / (1 - r_phi), r_phi)}
    print("eta %.2f: fit Fdr %.5f A %.4f; moments R_phi %.5f R_J %.5f A %.4f"
          % (ETA, fdr, rules["fit"][0], r_phi, r_j, rules["moments"][0]))
    zc, exact = transport(angles, dz)
    reference = np.mean(exact[(zc >= 2.0) & (zc <= 7.0)])
    print("transport (S_%d, dz %g mm): mean fluence 2-7 mm %.5f W/mm^2 per W/mm^2"
          % (2 * angles, dz, reference))
    for rule, (a, f) in rules.items():
        for model in ("surface", "extended"):
            z, phi = diffusion(model, a, f)
            mean = np.mean(phi[(z >= 2.0) & (z <= 7.0)])
            at = " ".join("%.3f" % (np.interp(d, z, phi) / np.interp(d, zc, exact)) for d in (2, 4, 6))
            print("%-8s %-8s / transport - 1 = %+6.2f %%  (ratio at 2, 4, 6 mm: %s)"
                  % (model, rule, 100.0 * (mean / reference - 1.0), at))


if __name__ == "__main__":
    main()
