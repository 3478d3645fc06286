#!/usr/bin/env python3
"""Generate snapshot_example.jsonl (docs/FORMATS.md): deterministic epochs in
both input forms. Linearised epochs: 8 GPS satellites, sigma 1 m, seeded
normal noise, a 50 m step on G02 from epoch 3, a second fault (-45 m on G06)
at epoch 5. Pseudorange epochs: receiver at the 0759 station's header
position, satellites on a 26,560 km sphere, clock 1234.5 m.
Run: python3 make_snapshot_example.py > snapshot_example.jsonl"""
import json, math, random

rng = random.Random(20261121)
SKY = [(0, 85), (45, 30), (100, 50), (150, 20), (200, 60), (250, 25), (300, 40), (340, 15)]

def linear(t, faults):
    sats = []
    for i, (az, el) in enumerate(SKY):
        r = rng.gauss(0, 1.0) + faults.get(i, 0.0)
        sats.append({"sys": "G", "prn": i + 1, "az_deg": az, "el_deg": el,
                     "residual_m": round(r, 4), "sigma_m": 1.0})
    return {"time_s": t, "sats": sats}

RX = (-3962108.673, 3381309.574, 3668678.638)

def geodetic(x, y, z):
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    p = math.hypot(x, y)
    lat = math.atan2(z, p * (1 - e2))
    for _ in range(10):
        n = a / math.sqrt(1 - e2 * math.sin(lat) ** 2)
        h = p / math.cos(lat) - n
        lat = math.atan2(z, p * (1 - e2 * n / (n + h)))
    return lat, math.atan2(y, x)

def ranges(t, faults):
    lat, lon = geodetic(*RX)
    sl, cl, so, co = math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon)
    e_, n_, u_ = (-so, co, 0), (-sl * co, -sl * so, cl), (cl * co, cl * so, sl)
    sats = []
    for i, (az, el) in enumerate(SKY):
        a, e = math.radians(az), math.radians(el)
        enu = (math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e))
        d = [enu[0] * e_[k] + enu[1] * n_[k] + enu[2] * u_[k] for k in range(3)]
        b = sum(p * q for p, q in zip(RX, d))
        c = sum(p * p for p in RX) - 26560000.0 ** 2
        rng_m = -b + math.sqrt(b * b - c)
        pos = [RX[k] + rng_m * d[k] for k in range(3)]
        pr = rng_m + 1234.5 + rng.gauss(0, 1.0) + faults.get(i, 0.0)
        sats.append({"sys": "G", "prn": i + 1, "pseudorange_m": round(pr, 4),
                     "position_m": [round(v, 4) for v in pos], "sigma_m": 1.0})
    return {"time_s": t, "sats": sats}

out = [linear(0, {}), linear(1, {}), linear(2, {}), linear(3, {1: 50.0}),
       linear(4, {1: 50.0}), linear(5, {1: 50.0, 5: -45.0}),
       ranges(6, {}), ranges(7, {1: 50.0})]
for e in out:
    print(json.dumps(e))
