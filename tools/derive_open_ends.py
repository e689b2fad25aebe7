#!/usr/bin/env python3
"""Interpolating (open) ends for the B-spline schemes with wide analysis filters.

Given a B-spline subdivision P with open ends (the open B-spline of §7.4 / §9.6: C_0 = F_0 and
C_last = F_last, regular rows inside) and a regular analysis row `a` with A P = I, derive the start
blocks of [A; B] and [P | Q] so that [A; B][P | Q] = I on every long enough lane (the end blocks are
the mirror images). Positions are lane positions: coarse j is centred at fine c0 + 2j, detail k at
e0 + 2k.

1. A: row 0 is C_0 = F_0 (interpolation). A row whose regular window leaves the lane, or for which
   the regular row does not give (A P)_j = e_j, is the local least-squares row of §9.5.1 over a
   window of the same width inside the lane: the row of (P_W^T P_W)^-1 P_W^T for C_j.
2. B, Q: regular rows b = mod(p) and columns q = mod(a) (h_k = (-1)^k w_{1-k}, the alternating
   flip of §9.5) wherever they fit, b P = 0 and A q = 0. The first details that fail get start
   blocks:
3. Q start columns: in {x near the start : A x = 0, regular B rows x = 0}, the vector closest
   (least squares) to the regular column cut to the lane.
4. B start rows: the shortest rows with B P = 0, B Q_start = I and B Q_regular = 0 (minimum norm).

Run: python3 tools/derive_open_ends.py   (prints the blocks as Rust constants and the check of
[A;B][P|Q] = I for every lane length from the shortest admissible one to 200). Needs numpy.
"""
import sys
import numpy as np

TOL = 1e-11


def mod(w):
    """Alternating flip of a filter centred at `cw` (half-integer allowed): taps and centre 1 - cw."""
    return np.array([(-1) ** t for t in range(len(w))], float) * np.array(w[::-1], float)


class Kind:
    """An open B-spline subdivision: coarse centres c0 + 2j, detail centres e0 + 2k, m(n)."""

    def __init__(s, name, p, c0, e0, m_of_n, start_rows):
        s.name, s.p, s.c0, s.e0, s.m_of_n, s.start_rows = name, np.array(p, float), c0, e0, m_of_n, start_rows

    def P(s, n):
        m = s.m_of_n(n)
        P = np.zeros((m, n))
        Lp = len(s.p)
        for j in range(n):
            lo = s.c0 + 2 * j - (Lp - 1) / 2
            for t in range(Lp):
                i = lo + t
                assert i == int(i)
                if 0 <= i < m:
                    P[int(i), j] = s.p[t]
        k = len(s.start_rows)
        P[:k] = 0
        P[m - k:] = 0
        for i, row in enumerate(s.start_rows):
            for c, w in row:
                P[i, c] = w
                P[m - 1 - i, n - 1 - c] = w
        return P


LINEAR = Kind("linear", [.5, 1, .5], 0, 1, lambda n: 2 * n - 1, [[(0, 1.0)]])
CHAIKIN = Kind("chaikin", [.25, .75, .75, .25], -0.5, 1.5, lambda n: 2 * n - 2,
               [[(0, 1.0)], [(0, .5), (1, .5)]])
CUBIC = Kind("cubic", [.125, .5, .75, .5, .125], -1, 2, lambda n: 2 * n - 3,
             [[(0, 1.0)], [(0, .5), (1, .5)], [(1, .75), (2, .25)],
              [(1, 3 / 16), (2, 11 / 16), (3, .125)], [(2, .5), (3, .5)]])


def place(w, centre, m):
    """Row/column vector of length m with taps w centred at `centre`; None if it leaves the lane."""
    lo = centre - (len(w) - 1) / 2
    assert lo == int(lo)
    lo = int(lo)
    if lo < 0 or lo + len(w) > m:
        return None
    v = np.zeros(m)
    v[lo:lo + len(w)] = w
    return v


def signed_dot(b, q):
    """b . q with both centred at the same position (B Q = I needs +1)."""
    m = 64
    return place(b, 31, m) @ place(q, 31, m) if len(b) % 2 else place(b, 31.5, m) @ place(q, 31.5, m)


def ls_row(P, W, j):
    K = sorted({int(c) for i in W for c in np.nonzero(np.abs(P[i]) > 0)[0]})
    PW = P[np.ix_(W, K)]
    A = np.linalg.solve(PW.T @ PW, PW.T)
    row = np.zeros(P.shape[0])
    row[W] = A[K.index(j)]
    return row


def lstsq_exact(M, rhs):
    x, *_ = np.linalg.lstsq(M, rhs, rcond=None)
    return x, np.abs(M @ x - rhs).max() if rhs.size else 0.0


def derive(kind, a, n=48):
    """Start blocks for analysis row `a` (symmetric about its centre) on open P `kind`."""
    a = np.array(a, float)
    P = kind.P(n)
    m, _ = P.shape
    s = m - n
    b, q = mod(kind.p), mod(a)
    if signed_dot(b, q) < 0:
        b = -b
    A = np.zeros((n, m))
    A[0, 0] = 1.0
    a_start = []  # (row j, first fine index, taps)
    for j in range(1, n // 2):
        c = kind.c0 + 2 * j
        v = place(a, c, m)
        if v is not None and np.allclose(v @ P, np.eye(n)[j], atol=TOL):
            A[j] = v
            continue
        lo = int(max(0, c - (len(a) - 1) / 2))
        W = list(range(lo, lo + len(a)))
        A[j] = ls_row(P, W, j)
        nz = np.nonzero(np.abs(A[j]) > 0)[0]
        a_start.append((j, int(nz[0]), A[j][nz[0]:nz[-1] + 1]))
    for j in range(n // 2, n):
        A[j] = A[n - 1 - j][::-1]
    # regular details valid from kb on
    def b_ok(k):
        v = place(b, kind.e0 + 2 * k, m)
        return v is not None and np.abs(v @ P).max() < TOL
    def q_ok(k):
        v = place(q, kind.e0 + 2 * k, m)
        return v is not None and np.abs(A @ v).max() < TOL
    kb = 0
    for k in range(s // 2):
        if not (b_ok(k) and q_ok(k)):
            kb = k + 1
    Breg = {k: place(b, kind.e0 + 2 * k, m) for k in range(kb, s - kb)}
    Qreg = {k: place(q, kind.e0 + 2 * k, m) for k in range(kb, s - kb)}
    # Q start columns
    for L in range(kb, m // 2):
        rows = [A[:, :L]] + [Breg[k][None, :L] for k in Breg if np.any(Breg[k][:L])]
        M = np.vstack(rows)
        u, sv, vt = np.linalg.svd(M)
        r = int((sv > 1e-9).sum())
        N = vt[r:].T  # L x dim
        if N.shape[1] < kb:
            continue
        Qs = []
        for k in range(kb):
            t = np.zeros(L)
            lo = int(kind.e0 + 2 * k - (len(q) - 1) / 2)
            for i, w in enumerate(q):
                if 0 <= lo + i < L:
                    t[lo + i] = w
            coef, *_ = np.linalg.lstsq(N, t, rcond=None)
            Qs.append(N @ coef)
        Qs = np.array(Qs).T
        if np.linalg.matrix_rank(Qs, tol=1e-9) == kb:
            break
    Lq = L
    Qstart = np.zeros((m, kb))
    Qstart[:Lq] = Qs
    # B start rows
    for Lb in range(kb, m // 2):
        cons = [P[:Lb].T]  # x P = 0  -> P^T x = 0
        rhs = [np.zeros((n, kb))]
        cons.append(Qstart[:Lb].T)
        rhs.append(np.eye(kb))
        for k, v in Qreg.items():
            if np.any(v[:Lb]):
                cons.append(v[None, :Lb])
                rhs.append(np.zeros((1, kb)))
        M = np.vstack(cons)
        R = np.vstack(rhs)
        X, res = lstsq_exact(M, R)
        if res < 1e-10:
            break
    Bstart = np.zeros((kb, m))
    Bstart[:, :Lb] = X.T
    return dict(A=A, a_start=a_start, kb=kb, Qstart=Qstart[:Lq], Bstart=Bstart[:, :Lb], b=b, q=q)


def assemble(kind, a, d, n):
    """Full [A;B] and [P|Q] for n coarse samples from the derived start blocks (end mirrored)."""
    a = np.array(a, float)
    if kind.m_of_n(n) < 2 * len(kind.start_rows) + 2:
        return None
    P = kind.P(n)
    m = P.shape[0]
    s = m - n
    b, q = d["b"], d["q"]
    A = np.zeros((n, m))
    A[0, 0] = A[n - 1, m - 1] = 1
    starts = {j: (f, t) for j, f, t in d["a_start"]}
    if any(f + len(t) > m for f, t in starts.values()) or 2 * (max(starts, default=0) + 1) > n:
        return None
    for j in range(1, n - 1):
        if j in starts:
            f, t = starts[j]
            A[j, f:f + len(t)] = t
        elif n - 1 - j in starts:
            f, t = starts[n - 1 - j]
            A[j, m - f - len(t):m - f] = t[::-1]
        else:
            v = place(a, kind.c0 + 2 * j, m)
            if v is None:
                return None
            A[j] = v
    kb = d["kb"]
    if 2 * kb > s:
        return None
    B = np.zeros((s, m))
    Q = np.zeros((m, s))
    Bs, Qs = d["Bstart"], d["Qstart"]
    if Bs.shape[1] > m or Qs.shape[0] > m:
        return None
    for k in range(kb):
        B[k, :Bs.shape[1]] = Bs[k]
        B[s - 1 - k, m - Bs.shape[1]:] = Bs[k][::-1]
        Q[:Qs.shape[0], k] = Qs[:, k]
        Q[m - Qs.shape[0]:, s - 1 - k] = Qs[::-1, k]
    for k in range(kb, s - kb):
        vb = place(b, kind.e0 + 2 * k, m)
        vq = place(q, kind.e0 + 2 * k, m)
        if vb is None or vq is None:
            return None
        B[k] = vb
        Q[:, k] = vq
    return np.vstack([A, B]), np.hstack([P, Q])


def check(kind, a, d, nmax=100):
    ok = []
    for n in range(3, nmax):
        r = assemble(kind, a, d, n)
        if r is None:
            continue
        AB, PQ = r
        err = np.abs(AB @ PQ - np.eye(AB.shape[0])).max()
        ok.append((n, err))
    return ok


if __name__ == "__main__" and len(sys.argv) == 1:
    a53 = [-.125, .25, .75, .25, -.125]
    d = derive(LINEAR, a53)
    for n, e in check(LINEAR, a53, d)[:6]:
        print("linear n", n, "err", e)
    print(d["a_start"], d["kb"], d["Qstart"].T, d["Bstart"])


# ----------------------------------------------------------------- exact regular rows, Rust output
def ls_regular_exact(kind, w):
    """Regular local least-squares row of window w, exactly (fractions), and its first offset
    from the coarse centre's fine index (periodic placement)."""
    import sympy as sp
    p = [sp.Rational(x).limit_denominator(64) for x in kind.p]
    Lp = len(p)
    cp = (Lp - 1) / 2  # p centred at the coarse centre
    cw = (w - 1) / 2
    # fine positions relative to the coarse centre, in half-samples when even
    even = Lp % 2 == 0
    off = 0.5 if even else 0.0
    W = [-cw + t for t in range(w)]  # positions relative to the centre (x.5 when even)
    ks = [k for k in range(-30, 31) if any(abs(x - 2 * k) <= cp for x in W)]
    PW = sp.zeros(len(W), len(ks))
    for i, x in enumerate(W):
        for c, k in enumerate(ks):
            d = x - 2 * k + cp
            if abs(d - round(d)) < 1e-9 and 0 <= round(d) < Lp:
                PW[i, c] = p[int(round(d))]
    A = (PW.T * PW).inv() * PW.T
    return [A[ks.index(0), i] for i in range(w)]


def fmt(x):
    import sympy as sp
    if isinstance(x, sp.Rational):
        return f"{int(x.p)}.0 / {int(x.q)}.0" if x.q != 1 else f"{float(x)!r}"
    return repr(float(x))


def rust_blocks(name, kind, a, d):
    out = []
    out.append(f"// {name}: generated by tools/derive_open_ends.py; do not edit by hand.")
    rows = ",\n".join(f"    ({j}, {f}, &[{', '.join(fmt(x) for x in t)}])" for j, f, t in d["a_start"])
    out.append(f"pub const A_START: &[(usize, usize, &[f64])] = &[\n{rows},\n];" if rows else
               "pub const A_START: &[(usize, usize, &[f64])] = &[];")
    def trim(v):
        v = list(v)
        while v and v[-1] == 0.0:
            v.pop()
        return v
    rows = ",\n".join(f"    &[{', '.join(fmt(x) for x in trim(r))}]" for r in d["Bstart"])
    out.append(f"pub const B_START: &[&[f64]] = &[\n{rows},\n];")
    rows = ",\n".join(f"    &[{', '.join(fmt(x) for x in trim(d['Qstart'][:, k]))}]" for k in range(d["kb"]))
    out.append(f"pub const Q_START: &[&[f64]] = &[\n{rows},\n];")
    return "\n".join(out)


def min_len(kind, a, d):
    c = check(kind, a, d, 140)
    good = [n for n, e in c if e < 1e-12]
    bad = [n for n, e in c if e >= 1e-12]
    n0 = min(good)
    assert all(n < n0 for n in bad), bad
    assert good == list(range(n0, 140)), "every longer lane reconstructs"
    return kind.m_of_n(n0)


def cdf97_taps(digits=30):
    """CDF 9/7 taps (analysis a with sum 1, synthesis p with sum 2) from the spectral factorisation
    of the degree-3 Daubechies polynomial P4(y) = 1 + 4y + 10y^2 + 20y^3, y = sin^2(w/2):
    p(w) = 2 cos^4(w/2) (1 - y/y_r) with y_r the real root, a(w) = cos^4(w/2) P4(y) / (1 - y/y_r)."""
    import sympy as sp
    y, z = sp.symbols("y z")
    P4 = 1 + 4 * y + 10 * y ** 2 + 20 * y ** 3
    yr = sp.re([r for r in sp.Poly(P4, y).nroots(n=digits + 10) if abs(sp.im(r)) < 1e-30][0])
    Qp = 1 - y / yr
    Qa = sp.quo(sp.Poly(P4, y), sp.Poly(Qp, y)).as_expr()
    Y = (2 - z - 1 / z) / 4
    C2 = (2 + z + 1 / z) / 4
    a = sp.expand(C2 ** 2 * Qa.subs(y, Y))
    p = sp.expand(2 * C2 ** 2 * Qp.subs(y, Y))

    def taps(e, half):
        pl = sp.Poly(sp.expand(e * z ** half), z)
        return [sp.N(pl.coeff_monomial(z ** k), digits) for k in range(2 * half + 1)]
    return taps(a, 4), taps(p, 3)


SCHEMES = {
    "linear": (LINEAR, lambda: [-0.125, 0.25, 0.75, 0.25, -0.125]),
    "linear-wide": (LINEAR, lambda: with_zeros_at_nyquist(LINEAR, ls_regular_exact(LINEAR, 9), 4)),
    "chaikin-wide": (CHAIKIN, lambda: with_zeros_at_nyquist(CHAIKIN, ls_regular_exact(CHAIKIN, 12), 3)),
    "cubic-wide": (CUBIC, lambda: with_zeros_at_nyquist(CUBIC, ls_regular_exact(CUBIC, 19), 4)),
}


def clean(x):
    """Round-off of the derivation removed: |x| < 1e-13 is 0, and values within 1e-13 of a
    fraction with a denominator up to 4096 become that fraction (checked again afterwards)."""
    from fractions import Fraction
    if abs(x) < 1e-13:
        return 0.0
    f = Fraction(x).limit_denominator(4096)
    return float(f) if abs(float(f) - x) < 1e-13 else x


def cleaned(d):
    d = dict(d)
    d["a_start"] = [(j, f, np.array([clean(x) for x in t])) for j, f, t in d["a_start"]]
    d["Bstart"] = np.vectorize(clean)(d["Bstart"])
    d["Qstart"] = np.vectorize(clean)(d["Qstart"])
    # trailing zeros of the start rows/columns dropped
    return d


def main():
    for name, (kind, fa) in SCHEMES.items():
        a_exact = fa()
        a = np.array([float(x) for x in a_exact])
        d = cleaned(derive(kind, a))
        ml = min_len(kind, a, d)
        worst = max(e for n, e in check(kind, a, d, 140) if kind.m_of_n(n) >= ml)
        print(f"// ===== {name}: regular a = [{', '.join(fmt(x) for x in a_exact)}]")
        print(f"// b = {[float(x) for x in d['b']]}\n// q = {[float(x) for x in d['q']]}")
        print(f"// shortest lane {ml}; max |[A;B][P|Q] - I| over n < 140: {worst:.1e}")
        print(f"pub const MIN_INTERPOLATING: usize = {ml};")
        print(rust_blocks(name, kind, a, d))
        print()




def with_zeros_at_nyquist(kind, a, zeros):
    """The filter nearest (least squares) to `a` among the rows with A P = I (biorthogonal to the
    regular p) and `zeros` zeros at the Nyquist frequency (sum_k (-1)^k k^z a_k = 0 for z < zeros),
    exactly (fractions)."""
    import sympy as sp
    L = len(a)
    p = [sp.Rational(x).limit_denominator(64) for x in kind.p]
    Lp = len(p)
    cw = sp.Rational(L - 1, 2)
    cp = sp.Rational(Lp - 1, 2)
    pos = [sp.Rational(t) - cw for t in range(L)]  # tap positions relative to the centre
    rows, d = [], []
    for j in range(-12, 13):
        r = [p[int(x - 2 * j + cp)] if 0 <= x - 2 * j + cp < Lp and (x - 2 * j + cp).is_integer else 0
             for x in pos]
        if any(r):
            rows.append(r)
            d.append(1 if j == 0 else 0)
    for z in range(zeros):
        rows.append([(-1) ** t * pos[t] ** z for t in range(L)])
        d.append(0)
    C = sp.Matrix(rows)
    dv = sp.Matrix(d)
    av = sp.Matrix(a)
    lam = (C * C.T).pinv() * (C * av - dv)
    out = av - C.T * lam
    return [sp.nsimplify(x) for x in out]


if __name__ == "__main__" and len(sys.argv) > 1 and sys.argv[1] == "rust":
    main()
