#!/usr/bin/env python3
"""The physical parameters of studies/multiarm_hand_vs_auto.ini, from the
training pieces only (python3, standard library; about 20 s):

    python3 examples/data/multiarm/fit_double_params.py

The compound double pendulum (examples/models/multiarm_double_pendulum.model)
depends on its parameters only through M11, M22, c = m2 L1 a2,
G1 = (m1 a1 + m2 L1) g and G2 = m2 a2 g (and the friction). G1 is kept at the
model file's value (it fixes the common scale); M11, M22, c and G2 minimise
the squared difference between the model's accelerations at the recorded
state and the central differences of the authors' derived rates, on every
7th row of train_01..26 (Nelder-Mead on the logarithms). The result is then
written as model parameters with m1 = m2 = 0.15 kg and g = 9.8083 as in the
model file. The friction is not identifiable this way (the fit drives it to
0); the study keeps the model file's 1e-4 N m s.
"""
import csv
import glob
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
G = 9.8083
M1 = M2 = 0.15
G1 = (0.15 * 0.085 + 0.15 * 0.17) * G  # the model file's (m1 a1 + m2 L1) g


def rows(pattern, every):
    out = []
    for path in sorted(glob.glob(os.path.join(HERE, "double", pattern))):
        d = [[float(x) for x in r] for r in list(csv.reader(open(path)))[1:]]
        for k in range(1, len(d) - 1, every):
            _, p1, p2, w1, w2 = d[k]
            dt = d[k + 1][0] - d[k - 1][0]
            acc1 = (d[k + 1][3] - d[k - 1][3]) / dt
            acc2 = (d[k + 1][4] - d[k - 1][4]) / dt
            out.append((math.cos(p1 - p2), math.sin(p1 - p2), math.sin(p1), math.sin(p2), w1, w2,
                        acc1, acc2))
    return out


def cost(x, data):
    """Mean squared acceleration error; x = log(M11, M22, c, G2)."""
    m11, m22, c, g2 = (math.exp(v) for v in x)
    total = 0.0
    for cs, sn, s1, s2, w1, w2, acc1, acc2 in data:
        r1 = -c * sn * w2 * w2 + G1 * s1
        r2 = c * sn * w1 * w1 + g2 * s2
        m12 = c * cs
        det = m11 * m22 - m12 * m12
        if det <= 0:
            return float("inf")
        total += ((m22 * r1 - m12 * r2) / det - acc1) ** 2 + ((m11 * r2 - m12 * r1) / det - acc2) ** 2
    return total / len(data)


def nelder_mead(f, x0, step, iterations):
    n = len(x0)
    pts = [list(x0)] + [[x0[j] + (step if j == i else 0) for j in range(n)] for i in range(n)]
    vals = [f(p) for p in pts]
    for _ in range(iterations):
        order = sorted(range(n + 1), key=lambda i: vals[i])
        pts, vals = [pts[i] for i in order], [vals[i] for i in order]
        c = [sum(p[j] for p in pts[:-1]) / n for j in range(n)]
        xr = [c[j] + (c[j] - pts[-1][j]) for j in range(n)]
        fr = f(xr)
        if fr < vals[0]:
            xe = [c[j] + 2 * (c[j] - pts[-1][j]) for j in range(n)]
            fe = f(xe)
            pts[-1], vals[-1] = (xe, fe) if fe < fr else (xr, fr)
        elif fr < vals[-2]:
            pts[-1], vals[-1] = xr, fr
        else:
            xc = [c[j] + 0.5 * (pts[-1][j] - c[j]) for j in range(n)]
            fc = f(xc)
            if fc < vals[-1]:
                pts[-1], vals[-1] = xc, fc
            else:
                for i in range(1, n + 1):
                    pts[i] = [pts[0][j] + 0.5 * (pts[i][j] - pts[0][j]) for j in range(n)]
                    vals[i] = f(pts[i])
    best = min(range(n + 1), key=lambda i: vals[i])
    return pts[best], vals[best]


def main():
    train, valid = rows("train_*.csv", 7), rows("validate_*.csv", 1)
    # Start: the model file's values (uniform 0.15 kg, 0.17 m rods).
    start = [0.15 * 0.17**2 / 12 + 0.15 * 0.085**2 + 0.15 * 0.17**2,
             0.15 * 0.17**2 / 12 + 0.15 * 0.085**2, 0.15 * 0.17 * 0.085, 0.15 * 0.085 * G]
    x0 = [math.log(v) for v in start]
    x, _ = nelder_mead(lambda x: cost(x, train), x0, 0.3, 1200)
    print("mean squared acceleration error [rad^2/s^4]: model file train %.4g validate %.4g; "
          "fitted train %.4g validate %.4g" % (cost(x0, train), cost(x0, valid), cost(x, train),
                                               cost(x, valid)))
    m11, m22, c, g2 = (math.exp(v) for v in x)
    print("M11 = %.4g, M22 = %.4g, m2 L1 a2 = %.4g, m2 a2 g = %.4g (G1 = %.4g kept)"
          % (m11, m22, c, g2, G1))
    l1 = c / (g2 / G)
    a2 = g2 / G / M2
    a1 = (G1 / G - M2 * l1) / M1
    i1 = m11 - M1 * a1 * a1 - M2 * l1 * l1
    i2 = m22 - M2 * a2 * a2
    print("params = L1=%.4g, a1=%.4g, a2=%.4g, I1=%.4g, I2=%.4g" % (l1, a1, a2, i1, i2))


if __name__ == "__main__":
    main()
