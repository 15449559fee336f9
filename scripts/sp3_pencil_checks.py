#!/usr/bin/env python3
"""Transport references for the sp3 solver's pencil-slab gap (issue 35).

Two independent computations, neither using the project's code
(Documentation/Solvers.md, "SP3", quotes their output):

  milne ETA    the Milne problem (isotropic scattering, c = 1) behind a
               Fresnel boundary of relative index ETA, by discrete ordinates
               (Gauss-Legendre, 48 directions per half range, step
               characteristics, 30 mfp in 1500 cells, solved directly):
               the extrapolation length z_ext of the linear asymptote, and
               the far-field amplitude of a normally incident beam's
               first-collision source, I = int exp(-z) phi_M(z) dz with
               phi_M the Milne solution of unit slope (by reciprocity the
               far-field R(rho) of a pencil beam is proportional to I).
               Printed beside the same two numbers from the SP3 boundary
               conditions (Sp3BoundaryCoefficients, restated here from the
               half-range moments r_m) and from diffusion (A of the Fresnel
               moments, and of the fitted Fdr with Farrell's source depth).
  mc N SEED MUA
               an analog Monte Carlo of the issue's pencil slab, laterally
               infinite (30 mm thick, mu_s 1/mm isotropic, mu_a MUA, eta
               1.3, Fresnel reflection with total internal reflection, no
               mesh): the exitance per W incident, averaged over annuli
               (rho edges below), with standard errors from batches of 200k.
               N = 4000000 takes about 5 minutes on one core.

Usage: sp3_pencil_checks.py milne 1.3 | sp3_pencil_checks.py mc 4000000 7 0.01
"""
import sys

import numpy as np

EDGES = np.array([0, 0.5, 1, 1.5, 2.5, 3, 3.5, 4.5, 5, 5.5, 6.5, 8, 9, 11, 12, 14, 16, 18, 19,
                  21, 22, 25])


def fresnel_inside(mu, eta):
    """Unpolarised Fresnel reflectance seen from inside at internal cosine mu."""
    mu = np.asarray(mu, float)
    s2 = eta ** 2 * (1 - mu ** 2)
    r = np.ones_like(mu)
    ok = s2 < 1
    ct, ci = np.sqrt(1 - s2[ok]), mu[ok]
    rs = (eta * ci - ct) / (eta * ci + ct)
    rp = (eta * ct - ci) / (eta * ct + ci)
    r[ok] = 0.5 * (rs ** 2 + rp ** 2)
    return r


def sp3_currents(eta):
    """F11, F12, F21, F22 of Sp3BoundaryCoefficients (restated)."""
    x, w = np.polynomial.legendre.leggauss(4000)
    mu, w = 0.5 * (x + 1), 0.5 * w
    rr = fresnel_inside(mu, eta)
    r = [np.sum(w * rr * mu ** m) for m in range(7)]
    a1, b1 = -r[1], 3 * r[2]
    c1 = 0.5 * (5 * r[3] - 3 * r[1])
    d1 = 0.5 * (3 * r[2] - 5 * r[4])
    a2 = -2.25 * r[1] + 7.5 * r[3] - 6.25 * r[5]
    b2 = 15.75 * r[2] - 52.5 * r[4] + 43.75 * r[6]
    m = np.array([[1 + b1, -7 * d1], [-3 * d1, 1 + b2]])
    f11, f21 = np.linalg.solve(m, [0.5 + a1, -(0.125 + c1)])
    f12, f22 = np.linalg.solve(m, [-(0.125 + c1), 7 / 24 + a2])
    return f11, f12, f21, f22, r


def milne(eta):
    f11, f12, f21, f22, r = sp3_currents(eta)
    lam = np.sqrt(35 / 9)
    z_sp3 = 1 / (3 * (f11 - f12 * f21 / (f22 + lam / 7)))
    c2 = -f21 * z_sp3 / (f22 + lam / 7)  # phi_2 (composite) at the surface, unit slope
    i_sp3 = 1 + z_sp3 - (2 / 3) * c2 / (1 + lam)
    a_moments = (1 + 3 * r[2]) / (1 - 2 * r[1])
    fdr = -1.44 / eta ** 2 + 0.71 / eta + 0.668 + 0.0636 * eta
    a_fit = (1 + fdr) / (1 - fdr)

    n = 48
    xg, wg = np.polynomial.legendre.leggauss(n)
    mup, wp = 0.5 * (xg + 1), 0.5 * wg
    rm = fresnel_inside(mup, eta)
    length, cells = 30.0, 1500
    d = length / cells
    xc = (np.arange(cells) + 0.5) * d
    e = np.exp(-d / mup)[:, None]

    def sweep(source, incoming):
        # source: (cells, k) isotropic emission per unit mu; mu_t = 1
        k = source.shape[1]
        phi = np.zeros((cells, k))
        psi = np.tile(incoming[:, None], (1, k)) if incoming is not None else np.zeros((n, k))
        for i in range(cells - 1, -1, -1):  # towards the Fresnel face
            out = psi * e + source[i][None, :] * (1 - e)
            phi[i] += (wp[:, None] * (source[i][None, :] + (psi - out) * mup[:, None] / d)).sum(0)
            psi = out
        psi = rm[:, None] * psi  # reflected back in
        for i in range(cells):
            out = psi * e + source[i][None, :] * (1 - e)
            phi[i] += (wp[:, None] * (source[i][None, :] + (psi - out) * mup[:, None] / d)).sum(0)
            psi = out
        return phi

    k = sweep(0.5 * np.eye(cells), None)
    b = sweep(np.zeros((cells, 1)), np.ones(n))[:, 0]
    phi = np.linalg.solve(np.eye(cells) - k, b)
    sel = (xc > 8) & (xc < 20)
    slope, offset = np.polyfit(xc[sel], phi[sel], 1)
    edges = np.arange(cells + 1) * d
    i_exact = np.sum((np.exp(-edges[:-1]) - np.exp(-edges[1:])) * phi / slope)
    print("eta %g: z_ext (mfp): transport %.4f, SP3 %.4f, P1 moments %.4f, P1 fit %.4f"
          % (eta, offset / slope, z_sp3, 2 * a_moments / 3, 2 * a_fit / 3))
    print("far-field amplitude I: transport %.4f, SP3 %.4f (%.4f), diffusion fit + Farrell "
          "%.4f (%.4f)" % (i_exact, i_sp3, i_sp3 / i_exact, 1 + 2 * a_fit / 3,
                           (1 + 2 * a_fit / 3) / i_exact))


def monte_carlo(photons, seed, mua):
    rng = np.random.default_rng(seed)
    eta, mus, thickness = 1.3, 1.0, 30.0
    mut = mua + mus
    specular = ((eta - 1) / (eta + 1)) ** 2
    batch = 200000
    tally = np.zeros(len(EDGES) - 1)
    tally2 = np.zeros(len(EDGES) - 1)
    batches = max(2, photons // batch)
    for _ in range(batches):
        x, y, z = np.zeros(batch), np.zeros(batch), np.zeros(batch)  # z: depth
        ux, uy, uz = np.zeros(batch), np.zeros(batch), np.ones(batch)
        w = np.ones(batch)
        alive = np.ones(batch, bool)
        t = np.zeros(len(EDGES) - 1)
        while alive.any():
            idx = np.nonzero(alive)[0]
            s = -np.log(rng.random(idx.size)) / mut
            zn = z[idx] + s * uz[idx]
            top, bottom = zn < 0, zn > thickness
            inside = ~(top | bottom)
            ii = idx[inside]
            x[ii] += s[inside] * ux[ii]
            y[ii] += s[inside] * uy[ii]
            z[ii] = zn[inside]
            w[ii] *= mus / mut
            cth = 2 * rng.random(ii.size) - 1
            ph = 2 * np.pi * rng.random(ii.size)
            sth = np.sqrt(1 - cth ** 2)
            ux[ii], uy[ii], uz[ii] = sth * np.cos(ph), sth * np.sin(ph), cth
            for hit, face in ((top, 0.0), (bottom, thickness)):
                ih = idx[hit]
                if ih.size == 0:
                    continue
                dist = (face - z[ih]) / uz[ih]
                x[ih] += dist * ux[ih]
                y[ih] += dist * uy[ih]
                z[ih] = face
                reflected = rng.random(ih.size) < fresnel_inside(np.abs(uz[ih]), eta)
                uz[ih[reflected]] *= -1
                escaped = ih[~reflected]
                if face == 0.0 and escaped.size:
                    h, _ = np.histogram(np.hypot(x[escaped], y[escaped]), bins=EDGES,
                                        weights=w[escaped])
                    t += h
                alive[escaped] = False
            low = np.nonzero(alive & (w < 1e-3))[0]
            survive = rng.random(low.size) < 0.1
            w[low[survive]] *= 10
            alive[low[~survive]] = False
        tally += t
        tally2 += t * t
    area = np.pi * (EDGES[1:] ** 2 - EDGES[:-1] ** 2)
    mean = tally / batches / batch / area * (1 - specular)
    se = np.sqrt(np.maximum(tally2 / batches - (tally / batches) ** 2, 0) / (batches - 1)) \
        / batch / area * (1 - specular)
    for a, b, m, e in zip(EDGES[:-1], EDGES[1:], mean, se):
        print("%g-%g mm %.5e (SE %.2f %%)" % (a, b, m, 100 * e / m))


if __name__ == "__main__":
    if len(sys.argv) >= 2 and sys.argv[1] == "milne":
        milne(float(sys.argv[2]) if len(sys.argv) > 2 else 1.3)
    elif len(sys.argv) >= 2 and sys.argv[1] == "mc":
        monte_carlo(int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]))
    else:
        print(__doc__)
        sys.exit(2)
