# Precision the parity path needs: the same whitened linearised model
# (unit lines of sight, sigma 1 m) in float32 and float64.
import numpy as np
rng = np.random.default_rng(1)
worst = {}
for n in (8, 16, 32):
    errs_d2, errs_w, errs_pl = [], [], []
    for trial in range(2000):
        az = rng.uniform(0, 2*np.pi, n); el = rng.uniform(np.radians(5), np.radians(89), n)
        H = np.column_stack([np.cos(el)*np.sin(az), np.cos(el)*np.cos(az), np.sin(el), np.ones(n)])
        z = rng.normal(size=n); z[1] += 20.0
        def stats(dt):
            Hq, zq = H.astype(dt), z.astype(dt)
            Q, R = np.linalg.qr(Hq, mode='complete')
            p = Q[:, 4:].T @ zq
            d2 = p @ p
            S = np.sum(Q[:, 4:]**2, axis=1)
            r = zq - Hq @ np.linalg.solve(R[:4], (Q[:, :4].T @ zq))
            w = r / np.sqrt(S)
            A = np.linalg.solve(R[:4], Q[:, :4].T)
            slope = np.sqrt(A[0]**2 + A[1]**2) / np.sqrt(S)
            return float(d2), w.astype(np.float64), float(slope.max())
        d64, w64, s64 = stats(np.float64); d32, w32, s32 = stats(np.float32)
        errs_d2.append(abs(d32-d64)/d64); errs_w.append(np.max(np.abs(w32-w64))); errs_pl.append(abs(s32-s64)/s64)
    print(f"n={n}: max rel err D^2 {max(errs_d2):.1e}, max abs err w_i {max(errs_w):.1e} sigma, max rel err HPL slope {max(errs_pl):.1e}")
print("float32 ulp at 2.0e7 m:", np.spacing(np.float32(2.0e7)), "m; at 2.66e7 m:", np.spacing(np.float32(2.66e7)), "m")
