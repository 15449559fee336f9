#!/usr/bin/env python3
"""Transport references for the sp3 solver's pencil-slab gap (issue 35).

Independent computations, none using the project's code
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
  orders N SEED MUA
               the same, and the exitance split by the number of scattering
               events before escape (1, 2, 3, >= 4).
  hybrid N SEED MUA [ETA]
               where SP_N's error near the beam lives: the slab in Hankel
               space (each radial wavenumber a 1-D P1 problem in depth; a
               mesh-free second computation of the sp3 solver's numbers)
               for SP1, SP3, SP5, SP7 (the planar P_N moment equations with
               the odd moments eliminated, Fresnel-Marshak conditions with
               the weights P_1..P_N); each with the beam's first-collision
               source, and as the hybrid "exact single scatter (exitance and
               the singly scattered fluence phi_1, Fresnel reflection at
               the lit face kept) + SP_N of the second-collision source
               mu_s phi_1"; then "scattering orders <= n from the Monte
               Carlo (N photons) + SP3 of the Monte Carlo's tallied source
               of scattering event n + 1", n = 1..5; the planar (k = 0)
               total reflectance against discrete ordinates. Ratios to the
               Monte Carlo over the annuli 2, 4, 6, 10, 15, 20 mm; ETA
               (default 1.3) the relative index of both faces. About 2
               minutes plus the Monte Carlo.
  transform MUA ETA KAPPA...
               int R(rho) I0(kappa rho) dA (the slab's transform at k =
               i kappa; kappa = 0: the total diffuse reflectance; towards
               mu_eff it weights the far field) of exact transport
               (discrete ordinates with 48 x 16 directions per half range)
               against SP1-SP7. About 2 minutes per kappa.

Usage: sp3_pencil_checks.py milne 1.3 | sp3_pencil_checks.py mc 4000000 7 0.01
       sp3_pencil_checks.py orders 4000000 7 0.01 | sp3_pencil_checks.py hybrid 4000000 7 0.01
       sp3_pencil_checks.py transform 0.01 1.3 0 0.1 0.15 0.165
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


def monte_carlo(photons, seed, mua, orders=False, sources=None):
    """The analog Monte Carlo; with `orders`, the exitance is also tallied by
    the number of scattering events before escape: 1, 2, 3 and >= 4. With
    `sources` = (radial edges, depth edges, n), the scattered weight of the
    scattering events 1..n is tallied in (rho, z) bins (W per W incident,
    the transmitted (1 - R_sp) included) and returned with the exitance by
    order (1..n, > n) in the annuli of EDGES (W/mm^2)."""
    rng = np.random.default_rng(seed)
    eta, mus, thickness = SLAB_ETA, 1.0, 30.0
    mut = mua + mus
    specular = ((eta - 1) / (eta + 1)) ** 2
    batch = 200000
    tally = np.zeros(len(EDGES) - 1)
    tally2 = np.zeros(len(EDGES) - 1)
    nord = 4  # orders 1, 2, 3, >= 4
    otally = np.zeros((nord, len(EDGES) - 1))
    otally2 = np.zeros((nord, len(EDGES) - 1))
    batches = max(2, photons // batch)
    if sources is not None:
        redges, zedges, nsrc = sources
        events = np.zeros((nsrc + 1, len(redges) - 1, len(zedges) - 1))
        byorder = np.zeros((nsrc + 2, len(EDGES) - 1))
    for _ in range(batches):
        x, y, z = np.zeros(batch), np.zeros(batch), np.zeros(batch)  # z: depth
        ux, uy, uz = np.zeros(batch), np.zeros(batch), np.ones(batch)
        w = np.ones(batch)
        alive = np.ones(batch, bool)
        t = np.zeros(len(EDGES) - 1)
        ot = np.zeros((nord, len(EDGES) - 1))
        order = np.zeros(batch, int)  # scattering events so far
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
            order[ii] += 1
            if sources is not None:
                for o in range(1, nsrc + 1):
                    sel = ii[order[ii] == o]
                    if sel.size:
                        h, _, _ = np.histogram2d(np.hypot(x[sel], y[sel]), z[sel],
                                                 bins=[redges, zedges], weights=w[sel])
                        events[o] += h
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
                    if sources is not None:
                        ob = np.minimum(order[escaped], nsrc + 1)
                        for o in range(nsrc + 2):
                            sel = escaped[ob == o]
                            h, _ = np.histogram(np.hypot(x[sel], y[sel]), bins=EDGES,
                                                weights=w[sel])
                            byorder[o] += h
                    if orders:
                        bucket = np.minimum(order[escaped], nord) - 1
                        for o in range(nord):
                            sel = bucket == o
                            ho, _ = np.histogram(np.hypot(x[escaped[sel]], y[escaped[sel]]),
                                                 bins=EDGES, weights=w[escaped[sel]])
                            ot[o] += ho
                alive[escaped] = False
            low = np.nonzero(alive & (w < 1e-3))[0]
            survive = rng.random(low.size) < 0.1
            w[low[survive]] *= 10
            alive[low[~survive]] = False
        tally += t
        tally2 += t * t
        otally += ot
        otally2 += ot * ot
    area = np.pi * (EDGES[1:] ** 2 - EDGES[:-1] ** 2)
    mean = tally / batches / batch / area * (1 - specular)
    if sources is not None:
        n = batches * batch
        return mean, events * (1 - specular) / n, byorder * (1 - specular) / n / area
    se = np.sqrt(np.maximum(tally2 / batches - (tally / batches) ** 2, 0) / (batches - 1)) \
        / batch / area * (1 - specular)
    for a, b, m, e in zip(EDGES[:-1], EDGES[1:], mean, se):
        print("%g-%g mm %.5e (SE %.2f %%)" % (a, b, m, 100 * e / m))
    if orders:
        omean = otally / batches / batch / area * (1 - specular)
        ose = np.sqrt(np.maximum(otally2 / batches - (otally / batches) ** 2, 0)
                      / (batches - 1)) / batch / area * (1 - specular)
        print("by scattering order (fraction of the annulus' exitance, SE of the value):")
        print("annulus | order 1 | order 2 | order 3 | order >= 4")
        for i, (a, b) in enumerate(zip(EDGES[:-1], EDGES[1:])):
            print("%g-%g mm | " % (a, b) + " | ".join(
                "%.5e (%.3f, SE %.2f %%)" % (omean[o, i], omean[o, i] / mean[i],
                                             100 * ose[o, i] / max(omean[o, i], 1e-300))
                for o in range(nord)))


# ---- The slab in Hankel space (mode "hybrid"). The laterally infinite slab
# (30 mm, mu_s 1/mm isotropic, eta 1.3 both faces, normal pencil beam at the
# origin) transformed in rho, f~(k, z) = 2 pi int f(rho, z) J0(k rho) rho drho:
# each radial wavenumber k is a 1-D problem in z. A mesh-free second
# computation of the mesh solver's numbers, and the way to try source models.

HYB_ANNULI = [(1.5, 2.5), (3.5, 4.5), (5.5, 6.5), (9, 11), (14, 16), (19, 21)]
SLAB_L, SLAB_ETA, SLAB_MUS = 30.0, 1.3, 1.0


def depth_grid(h0=0.002, ratio=1.04, hmax=0.25):
    """P1 nodes in z: 2 um at the lit face, growing 4 % per cell to 0.25 mm."""
    z, h = [0.0], h0
    while z[-1] < SLAB_L:
        z.append(min(z[-1] + h, SLAB_L))
        h = min(h * ratio, hmax)
    return np.array(z)


def spn_setup(order, mua, eta=None):
    """SP_N (N = order, odd) for g = 0: the planar P_N moment equations
    (Solvers.md, SP3 "Derivation") with the odd moments eliminated,
    -D phi'' + S phi = Q e_0 in the even moments phi = (phi_0, phi_2, ...),
    and the Fresnel-Marshak conditions with the weights P_1, P_3, ..., P_N
    solved for the odd moments at the lit face: phi_odd = B phi_even; the
    exitance E . phi_even. N = 3 is Sp3Solver's system (the composite
    moments are a change of unknowns)."""
    eta = SLAB_ETA if eta is None else eta
    mut = mua + SLAB_MUS
    sig = np.array([mua] + [mut] * order)
    ne = (order + 1) // 2
    ev, od = [2 * i for i in range(ne)], [2 * i + 1 for i in range(ne)]
    g = np.zeros((ne, ne))  # phi_odd = g phi_even'
    p = np.zeros((ne, ne))  # the flux of even equation n: p phi_odd
    for i, n in enumerate(od):
        if n + 1 <= order:
            g[i, (n + 1) // 2] -= (n + 1) / (2 * n + 1) / sig[n]
        g[i, (n - 1) // 2] -= n / (2 * n + 1) / sig[n]
    for i, n in enumerate(ev):
        p[i, i] += (n + 1) / (2 * n + 1)
        if n >= 1:
            p[i, i - 1] += n / (2 * n + 1)
    x, w = np.polynomial.legendre.leggauss(400)
    mu, w = 0.5 * (x + 1), 0.5 * w
    refl = fresnel_inside(mu, eta)
    pn = np.array([np.polynomial.legendre.legval(mu, np.eye(order + 1)[n])
                   for n in range(order + 1)])
    pm = pn * ((-1.0) ** np.arange(order + 1))[:, None]  # P_n(-mu)
    scale = (2 * np.arange(order + 1) + 1) / (4 * np.pi)
    m = np.array([[np.sum(w * (pn[n] - refl * pm[n]) * pn[j]) * scale[n]
                   for n in range(order + 1)] for j in od])
    b = -np.linalg.solve(m[:, od], m[:, ev])
    e = np.array([2 * np.pi * np.sum(w * (1 - refl) * pm[n] * mu) * scale[n]
                  for n in range(order + 1)])
    return -p @ g, np.diag(sig[ev]), p @ b, e[ev] + e[od] @ b


def spn_exitance(order, mua, k, z, load, k2=None):
    """The exitance at the lit face (Hankel transform, W per W) of SP_N with
    the isotropic source whose P1 load int Q v dz is `load` (len(k), len(z)):
    P1 Galerkin in z (consistent mass), block Thomas over the nodes for all k.
    `k2` (optional) gives k^2 directly (negative: the transform at k = i
    kappa, int R(rho) I0(kappa rho) dA)."""
    d, sm, bd, e = spn_setup(order, mua)
    k2 = k ** 2 if k2 is None else np.asarray(k2, float)
    ne, h, nn, kk = d.shape[0], np.diff(z), len(z), len(k2)
    diag = np.zeros((kk, nn, ne, ne))
    off = np.zeros((kk, nn - 1, ne, ne))  # upper = lower (both symmetric in the nodes)
    mk = sm[None] + k2[:, None, None] * d[None]
    for i in range(nn - 1):
        a = d[None] / h[i] + mk * h[i] / 3
        diag[:, i] += a
        diag[:, i + 1] += a
        off[:, i] = -d[None] / h[i] + mk * h[i] / 6
    diag[:, 0] -= bd  # both faces: the flux p phi_odd of the Marshak conditions
    diag[:, -1] -= bd
    rhs = np.zeros((kk, nn, ne))
    rhs[:, :, 0] = load
    cp, dp = np.zeros_like(off), np.zeros_like(rhs)
    inv = np.linalg.inv(diag[:, 0])
    cp[:, 0], dp[:, 0] = inv @ off[:, 0], np.einsum('kij,kj->ki', inv, rhs[:, 0])
    for i in range(1, nn):
        inv = np.linalg.inv(diag[:, i] - off[:, i - 1] @ cp[:, i - 1])
        if i < nn - 1:
            cp[:, i] = inv @ off[:, i]
        dp[:, i] = np.einsum('kij,kj->ki', inv,
                             rhs[:, i] - np.einsum('kij,kj->ki', off[:, i - 1], dp[:, i - 1]))
    x = dp[:, -1]
    for i in range(nn - 2, -1, -1):
        x = dp[:, i] - np.einsum('kij,kj->ki', cp[:, i], x)
    return x @ e


def p1_load(z, q):
    """int q v dz of the P1 interpolant of nodal values q (len(k), len(z))."""
    h = np.diff(z)
    load = np.zeros(q.shape)
    load[:, :-1] += q[:, :-1] * h / 3 + q[:, 1:] * h / 6
    load[:, 1:] += q[:, 1:] * h / 3 + q[:, :-1] * h / 6
    return load


def annulus_means(transform, annuli=HYB_ANNULI):
    """Means over annuli of the inverse Hankel transform of a smooth function
    of k given at SOLVE_K (spline in log k onto a fine trapezoid grid to
    200 / mm): (1 / 2 pi) int f(k) k W(k) dk, W the annulus mean of J0(k rho).
    Steps of 0.001 / mm to 5 / mm, 0.002 beyond: halving them changes the
    20 mm annulus by 0.1 % (steps of 0.05 beyond 40 / mm were 2-3 % off
    there for the first-collision line source)."""
    from scipy.interpolate import CubicSpline
    from scipy.special import j1
    k = np.concatenate([np.arange(0, 5, 0.001), np.arange(5, 200.001, 0.002)])
    wk = np.zeros_like(k)
    wk[:-1] += np.diff(k) / 2
    wk[1:] += np.diff(k) / 2
    f = CubicSpline(np.log(SOLVE_K[1:]), transform[1:])(np.log(np.maximum(k, SOLVE_K[1])))
    f[k < SOLVE_K[1]] = transform[0]
    out = []
    for a, b in annuli:
        with np.errstate(invalid='ignore', divide='ignore'):
            wa = 2 * (b * j1(k * b) - a * j1(k * a)) / (k * (b * b - a * a))
        wa[k == 0] = 1.0
        out.append(np.sum(wk * f * wa * k) / (2 * np.pi))
    return np.array(out)


SOLVE_K = np.concatenate([[0.0], np.geomspace(1e-3, 200, 500)])


def single_scatter_fluence(mua, z):
    """Hankel transform (SOLVE_K, z) of the singly scattered fluence phi_1 of
    the first-collision source q1(s) = T mu_s exp(-mu_t s) on the axis, exact:
    phi_1(x) = int q1(s) exp(-mu_t R) / (4 pi R^2) ds plus the same reflected
    once at the lit face with the Fresnel R(cos) (other reflections: < e^-30).
    The direct part by Sommerfeld's identity, (1/2) int_{mu_t}^inf
    exp(-|z - s| u) / u dt, u = sqrt(t^2 + k^2), with the s integral in
    closed form (t = mu_t / m, m = x^2, Gauss-Legendre); the reflected part
    in real space (log grid in s) and transformed by a rho quadrature."""
    from scipy.special import j0
    mut = mua + SLAB_MUS
    amp = (1 - ((SLAB_ETA - 1) / (SLAB_ETA + 1)) ** 2) * SLAB_MUS
    x, wx = np.polynomial.legendre.leggauss(200)
    x, wx = 0.5 * (x + 1), 0.5 * wx
    m, wm = x * x, 2 * x * wx
    k = SOLVE_K[:, None, None]
    root = np.sqrt(mut * mut + k * k * m * m)
    u = root / m
    zz = z[None, :, None]
    du, ez = u - mut, np.exp(-mut * zz)
    with np.errstate(over='ignore', invalid='ignore', divide='ignore'):
        above = np.where(du * zz > 1e-12, -ez * np.expm1(-du * zz) / np.where(du == 0, 1, du),
                         zz * ez)
    below = (ez - np.exp(np.minimum(u * zz - (u + mut) * SLAB_L, 0))) / (u + mut)
    direct = 0.5 * amp * np.sum(wm * mut / (m * root) * (above + below), axis=-1)
    rho = np.concatenate([np.geomspace(1e-6, 1, 300)[:-1], np.arange(1, 25.0001, 0.005)])
    wr = np.zeros_like(rho)
    wr[:-1] += np.diff(rho) / 2
    wr[1:] += np.diff(rho) / 2
    s = np.concatenate([[0.0], np.geomspace(1e-7, 40, 400)])
    ws = np.zeros_like(s)
    ws[:-1] += np.diff(s) / 2
    ws[1:] += np.diff(s) / 2
    near = z[z < 20]
    real = np.zeros((len(near), len(rho)))
    for i, depth in enumerate(near):
        d = depth + s[:, None]
        r = np.sqrt(rho[None, :] ** 2 + d * d)
        f = fresnel_inside((d / r).ravel(), SLAB_ETA).reshape(r.shape) \
            * np.exp(-mut * (s[:, None] + r)) / (4 * np.pi * r * r)
        real[i] = amp * np.sum(ws[:, None] * f, axis=0)
    reflected = np.zeros_like(direct)
    reflected[:, :len(near)] = j0(np.outer(SOLVE_K, rho)) @ (2 * np.pi * (rho * wr)[:, None] * real.T)
    return direct + reflected


def single_scatter_exitance(mua, annuli=HYB_ANNULI):
    """The singly scattered exitance, exact, averaged over annuli:
    int q1(s) (1 - R(cos)) cos exp(-mu_t R) / (4 pi R^2) ds, cos = s / R."""
    mut = mua + SLAB_MUS
    amp = (1 - ((SLAB_ETA - 1) / (SLAB_ETA + 1)) ** 2) * SLAB_MUS
    s = np.concatenate([[0.0], np.geomspace(1e-7, 40, 600)])
    ws = np.zeros_like(s)
    ws[:-1] += np.diff(s) / 2
    ws[1:] += np.diff(s) / 2
    xg, wg = np.polynomial.legendre.leggauss(40)
    out = []
    for a, b in annuli:
        rho = a + (b - a) * 0.5 * (xg + 1)
        wr = (b - a) * wg * rho / (b * b - a * a)
        r = np.sqrt(rho[None, :] ** 2 + s[:, None] ** 2)
        c = s[:, None] / r
        f = amp * (1 - fresnel_inside(c.ravel(), SLAB_ETA).reshape(c.shape)) * c \
            * np.exp(-mut * (s[:, None] + r)) / (4 * np.pi * r * r)
        out.append(np.sum(ws[:, None] * f * wr[None, :]))
    return np.array(out)


def planar_reflectance(mua, kappa=0.0, azimuths=1):
    """Exact transport (discrete ordinates as in milne(), 48 directions per
    half range times `azimuths` Gauss-Legendre azimuths on [0, pi], 1500
    cells) of the slab's transform at k = i kappa (1/mm; the lateral
    dependence exp(kappa x), so each direction's total coefficient is
    mu_t - kappa Omega_x): int R(rho) I0(kappa rho) dA of the normally
    incident beam (kappa = 0: the total diffuse reflectance), and its
    single-scatter part."""
    c, mut = SLAB_MUS / (mua + SLAB_MUS), mua + SLAB_MUS
    amp = (1 - ((SLAB_ETA - 1) / (SLAB_ETA + 1)) ** 2) * SLAB_MUS
    xg, wg = np.polynomial.legendre.leggauss(48)
    xa, wa = np.polynomial.legendre.leggauss(azimuths)
    mup = np.repeat(0.5 * (xg + 1), azimuths)
    wp = np.repeat(0.5 * wg, azimuths) * np.tile(0.5 * wa, 48)
    sig = 1 - kappa / mut * np.sqrt(1 - mup ** 2) * np.cos(np.tile(0.5 * np.pi * (xa + 1), 48))
    rm = fresnel_inside(mup, SLAB_ETA)
    cells = 1500
    d = SLAB_L * mut / cells  # optical depth
    edges = np.arange(cells + 1) * d
    e = np.exp(-sig * d / mup)[:, None]
    sg = sig[:, None]

    def sweep(source):
        phi, psi = np.zeros(source.shape), np.zeros((len(mup), source.shape[1]))
        for i in range(cells - 1, -1, -1):
            out = psi * e + source[i][None, :] / sg * (1 - e)
            phi[i] += (wp[:, None] * (source[i][None, :] + (psi - out) * mup[:, None] / d)
                       / sg).sum(0)
            psi = out
        exit_ = (wp[:, None] * (1 - rm[:, None]) * psi * mup[:, None]).sum(0)
        psi = rm[:, None] * psi
        for i in range(cells):
            out = psi * e + source[i][None, :] / sg * (1 - e)
            phi[i] += (wp[:, None] * (source[i][None, :] + (psi - out) * mup[:, None] / d)
                       / sg).sum(0)
            psi = out
        return phi, exit_

    kphi, kexit = np.zeros((cells, cells)), np.zeros(cells)
    for j in range(0, cells, 250):  # the scattering kernel, 250 unit sources at a time
        unit = np.zeros((cells, min(250, cells - j)))
        unit[np.arange(j, j + unit.shape[1]), np.arange(unit.shape[1])] = 0.5 * c
        kphi[:, j:j + unit.shape[1]], kexit[j:j + unit.shape[1]] = sweep(unit)
    q = amp / mut * (np.exp(-edges[:-1]) - np.exp(-edges[1:])) / d
    b, bexit = sweep(0.5 * q[:, None])
    phi = np.linalg.solve(np.eye(cells) - kphi, b[:, 0])
    return bexit[0] + kexit @ phi, bexit[0]


def hybrid(photons, seed, mua):
    """Where SP_N's error lives (Solvers.md, SP3, pencil slab): R(rho) over the
    annuli of the Monte Carlo (photons, seed) and, in Hankel space,
    SP_N (N = 1, 3, 5, 7) of the first-collision source; the hybrid 'exact
    single scatter + SP_N of the second-collision source mu_s phi_1'; and the
    hybrids 'scattering orders <= n from the Monte Carlo + SP3 of its
    tallied source of scattering event n + 1', n = 1..5."""
    global EDGES
    z = depth_grid()
    amp = (1 - ((SLAB_ETA - 1) / (SLAB_ETA + 1)) ** 2) * SLAB_MUS
    mut = mua + SLAB_MUS
    exact0, single0 = planar_reflectance(mua)
    print("planar (k = 0) total diffuse reflectance: transport %.5f (single scatter %.5f)"
          % (exact0, single0))
    line = p1_load(z, amp * np.exp(-mut * z)[None, :] * np.ones((len(SOLVE_K), 1)))
    phi1 = single_scatter_fluence(mua, z)
    r1 = single_scatter_exitance(mua)
    second = p1_load(z, SLAB_MUS * phi1)
    model = {}
    for order in (1, 3, 5, 7):
        rt = spn_exitance(order, mua, SOLVE_K, z, line)
        print("SP%d planar total diffuse reflectance %.5f (/ transport %.4f)"
              % (order, rt[0], rt[0] / exact0))
        model["SP%d" % order] = annulus_means(rt)
        model["SP%d hybrid-1" % order] = r1 + annulus_means(
            spn_exitance(order, mua, SOLVE_K, z, second))
    saved = EDGES
    EDGES = np.array(sorted({e for pair in HYB_ANNULI for e in pair}))
    pick = [list(EDGES).index(a) for a, _ in HYB_ANNULI]
    redges = np.concatenate([[0.0], np.geomspace(1e-4, 1, 100), np.arange(1.02, 30.0001, 0.02)])
    mean, events, byorder = monte_carlo(photons, seed, mua, sources=(redges, z, 6))
    EDGES = saved
    from scipy.special import j0
    jr = j0(np.outer(SOLVE_K, 0.5 * (redges[1:] + redges[:-1])))
    h = np.diff(z)
    for n in range(1, 6):
        density = jr @ events[n + 1] / h[None, :]  # Hankel transform, per mm of depth
        load = np.zeros((len(SOLVE_K), len(z)))
        load[:, :-1] += density * h / 2
        load[:, 1:] += density * h / 2
        model["SP3 + MC orders <= %d" % n] = byorder[:n + 1].sum(0)[pick] + annulus_means(
            spn_exitance(3, mua, SOLVE_K, z, load))
    mc = mean[pick]
    print("single scatter, exact / Monte Carlo order 1: " + ", ".join(
        "%g-%g mm %.3f" % (a, b, v / t) for (a, b), v, t in zip(HYB_ANNULI, r1, byorder[1][pick])
        if t > 0))
    print("annulus | Monte Carlo | " + " | ".join(model))
    for i, (a, b) in enumerate(HYB_ANNULI):
        print("%g-%g mm | %.4e | " % (a, b, mc[i]) + " | ".join(
            "%.3f" % (v[i] / mc[i]) for v in model.values()))



def transform(mua, kappas):
    """int R(rho) I0(kappa rho) dA (the transform at k = i kappa, weighting
    the far field more as kappa grows towards mu_eff) of exact transport
    (planar_reflectance with 16 azimuths) against SP_N of the beam's
    first-collision source."""
    z = depth_grid()
    mut = mua + SLAB_MUS
    amp = (1 - ((SLAB_ETA - 1) / (SLAB_ETA + 1)) ** 2) * SLAB_MUS
    load = p1_load(z, amp * np.exp(-mut * z)[None, :])
    for kappa in kappas:
        exact, _ = planar_reflectance(mua, kappa, 16)
        print("kappa %.3f /mm: transport %.5f | " % (kappa, exact) + " | ".join(
            "SP%d / transport %.4f" % (o, spn_exitance(o, mua, None, z, load, [-kappa ** 2])[0]
                                        / exact) for o in (1, 3, 5, 7)), flush=True)


if __name__ == "__main__":
    if len(sys.argv) >= 2 and sys.argv[1] == "milne":
        milne(float(sys.argv[2]) if len(sys.argv) > 2 else 1.3)
    elif len(sys.argv) >= 4 and sys.argv[1] == "transform":
        SLAB_ETA = float(sys.argv[3])
        transform(float(sys.argv[2]), [float(a) for a in sys.argv[4:]])
    elif len(sys.argv) >= 2 and sys.argv[1] == "hybrid":
        if len(sys.argv) > 5:
            SLAB_ETA = float(sys.argv[5])
        hybrid(int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]))
    elif len(sys.argv) >= 2 and sys.argv[1] in ("mc", "orders"):
        monte_carlo(int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]),
                    orders=sys.argv[1] == "orders")
    else:
        print(__doc__)
        sys.exit(2)
