//! Writes the seed corpus of `frame_decoder` (valid frames of every kind,
//! and a few damaged ones) into `corpus/frame_decoder/`.
//! `cd fuzz && cargo run --bin make_seeds`
use raim_core::{Config, FiRule, LinearObservation, RangeObservation, SatId, System};
use raim_proto::frame::encode;
use raim_proto::message::{CommandRef, RequestRef};

fn frame(r: &RequestRef<'_>) -> Vec<u8> {
    let mut s = vec![0u8; 1 << 16];
    let mut o = vec![0u8; 1 << 16];
    encode(r, &mut s, &mut o).expect("encode").to_vec()
}

fn main() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus/frame_decoder");
    std::fs::create_dir_all(&dir).expect("corpus dir");
    let lin: Vec<LinearObservation> = (0..8)
        .map(|i| {
            LinearObservation::from_az_el(
                SatId::new(System::Gps, i + 1),
                i as f64 * 0.7,
                0.2 + i as f64 * 0.15,
                0.1 * i as f64,
            )
        })
        .collect();
    let rng: Vec<RangeObservation> = (0..6)
        .map(|i| RangeObservation {
            id: SatId::new(
                if i % 2 == 0 {
                    System::Gps
                } else {
                    System::Galileo
                },
                i + 1,
            ),
            pseudorange_m: 2.1e7 + 1e5 * i as f64,
            position_m: [1.5e7, -1.0e7 + 1e6 * i as f64, 2.0e7],
            sigma_m: if i == 3 { None } else { Some(1.5) },
        })
        .collect();
    let cfg = Config {
        rule: FiRule::LraimGaussian { kappa: 50.0 },
        ..Config::default()
    };
    let many: Vec<LinearObservation> = (0..40)
        .map(|i| LinearObservation {
            id: SatId::new(System::Beidou, i),
            ..lin[0]
        })
        .collect();
    let seeds: Vec<(&str, Vec<u8>)> = vec![
        (
            "status",
            frame(&RequestRef {
                seq: 0,
                command: CommandRef::Status,
            }),
        ),
        (
            "configure",
            frame(&RequestRef {
                seq: 1,
                command: CommandRef::Configure(&cfg),
            }),
        ),
        ("linear8", frame(&RequestRef::linear(2, 3.0, &lin))),
        (
            "ranges6",
            frame(&RequestRef::ranges(3, 1.7e9, Some([1.0, 2.0, 3.0]), &rng)),
        ),
        ("toomany", frame(&RequestRef::linear(4, 0.0, &many))),
        (
            "two",
            [
                frame(&RequestRef::linear(5, 0.0, &lin)),
                frame(&RequestRef {
                    seq: 6,
                    command: CommandRef::Status,
                }),
            ]
            .concat(),
        ),
        ("truncated", {
            let f = frame(&RequestRef::ranges(7, 0.0, None, &rng));
            [&f[..f.len() / 2], &[0u8][..]].concat()
        }),
        ("flipped", {
            let mut f = frame(&RequestRef::linear(8, 0.0, &lin));
            f[20] ^= 0x10;
            f
        }),
    ];
    for (name, bytes) in seeds {
        std::fs::write(dir.join(name), bytes).expect("write seed");
    }
    araim_seeds();
}

/// Seeds of `araim_server`: ARAIM epochs over the ISM the target
/// puts in force (GPS and Galileo 1-6), a fault, ISM frames good and bad.
fn araim_seeds() {
    use raim_proto::araim_msg::{AraimCommandRef, IsmFrameRef, IsmSat, WireAraimConfig};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus/araim_server");
    std::fs::create_dir_all(&dir).expect("corpus dir");
    let ids: Vec<SatId> = (0..12u8)
        .map(|i| {
            SatId::new(
                if i % 2 == 0 {
                    System::Gps
                } else {
                    System::Galileo
                },
                i / 2 + 1,
            )
        })
        .collect();
    let epoch: Vec<LinearObservation> = ids
        .iter()
        .enumerate()
        .map(|(i, &id)| {
            LinearObservation::from_az_el(
                id,
                i as f64 * 2.4,
                0.2 + (i as f64 * 0.5) % 1.3,
                0.05 * i as f64 - 0.3,
            )
        })
        .collect();
    let mut faulted = epoch.clone();
    faulted[3].residual_m += 80.0;
    let ism: Vec<IsmSat> = ids
        .iter()
        .map(|&id| IsmSat {
            id,
            sigma_ura_m: 0.75,
            sigma_ure_m: 0.5,
            b_nom_m: 0.5,
            p_sat: 1e-5,
        })
        .collect();
    let mut bad = ism.clone();
    bad[2].p_sat = 1.0;
    let mut p_const = [None; 5];
    p_const[System::Gps.index()] = Some(1e-4);
    p_const[System::Galileo.index()] = Some(1e-4);
    let ism_cmd = |seq, sats: &[IsmSat]| {
        frame(&RequestRef {
            seq,
            command: CommandRef::Araim(AraimCommandRef::Ism(IsmFrameRef {
                config: WireAraimConfig::default(),
                p_const,
                sats,
            })),
        })
    };
    let epoch_cmd = |seq, sats: &[LinearObservation]| {
        frame(&RequestRef {
            seq,
            command: CommandRef::Araim(AraimCommandRef::Epoch { time_s: 1.0, sats }),
        })
    };
    let ranges = ranges12(&ids);
    let mut ranges_faulted = ranges.clone();
    ranges_faulted[3].pseudorange_m += 80.0;
    let mut ranges_nan = ranges.clone();
    ranges_nan[5].pseudorange_m = f64::NAN;
    let ranges_cmd = |seq, sats: &[RangeObservation]| {
        frame(&RequestRef {
            seq,
            command: CommandRef::Araim(AraimCommandRef::Ranges {
                time_s: 2.0,
                apriori_m: Some(RX_M),
                sats,
            }),
        })
    };
    let seeds: Vec<(&str, Vec<u8>)> = vec![
        ("ranges12", ranges_cmd(1, &ranges)),
        ("ranges12_faulted", ranges_cmd(1, &ranges_faulted)),
        ("ranges12_nan", ranges_cmd(1, &ranges_nan)),
        (
            "ranges12_no_apriori",
            frame(&RequestRef {
                seq: 1,
                command: CommandRef::Araim(AraimCommandRef::Ranges {
                    time_s: 2.0,
                    apriori_m: None,
                    sats: &ranges,
                }),
            }),
        ),
        ("epoch12", epoch_cmd(1, &epoch)),
        ("faulted12", epoch_cmd(1, &faulted)),
        (
            "ism_then_epoch",
            [ism_cmd(1, &ism), epoch_cmd(2, &epoch)].concat(),
        ),
        ("bad_ism", ism_cmd(1, &bad)),
        (
            "lock_then_ism",
            [
                frame(&RequestRef {
                    seq: 1,
                    command: CommandRef::Lock,
                }),
                ism_cmd(2, &ism),
            ]
            .concat(),
        ),
    ];
    for (name, bytes) in seeds {
        std::fs::write(dir.join(name), bytes).expect("write seed");
    }
}

/// A receiver on the ground (ECEF, m) for the pseudorange seeds.
const RX_M: [f64; 3] = [-3_962_108.673, 3_381_309.574, 3_668_678.638];

/// Pseudoranges of `ids` from satellites at GPS orbit radius spread over
/// the sky above [`RX_M`], with a receiver clock per constellation
/// (`AraimCommand::Ranges`, protocol 8).
fn ranges12(ids: &[SatId]) -> Vec<RangeObservation> {
    const ORBIT_RADIUS_M: f64 = 26_560_000.0;
    let norm = RX_M.iter().map(|v| v * v).sum::<f64>().sqrt();
    let up = RX_M.map(|v| v / norm);
    let east = {
        let e = [-up[1], up[0], 0.0];
        let n = (e[0] * e[0] + e[1] * e[1]).sqrt();
        e.map(|v| v / n)
    };
    let north = [
        up[1] * east[2] - up[2] * east[1],
        up[2] * east[0] - up[0] * east[2],
        up[0] * east[1] - up[1] * east[0],
    ];
    ids.iter()
        .enumerate()
        .map(|(i, &id)| {
            let az = i as f64 * 2.4;
            let el = 0.2 + (i as f64 * 0.5) % 1.3;
            let d: [f64; 3] = std::array::from_fn(|k| {
                el.cos() * (az.sin() * east[k] + az.cos() * north[k]) + el.sin() * up[k]
            });
            let b: f64 = RX_M.iter().zip(d.iter()).map(|(p, q)| p * q).sum();
            let c = norm * norm - ORBIT_RADIUS_M * ORBIT_RADIUS_M;
            let range = -b + (b * b - c).sqrt();
            let clock = if id.system == System::Gps {
                1234.5
            } else {
                -987.0
            };
            RangeObservation {
                id,
                pseudorange_m: range + clock + 0.3 * ((i % 5) as f64 - 2.0),
                position_m: std::array::from_fn(|k| RX_M[k] + range * d[k]),
                sigma_m: None,
            }
        })
        .collect()
}
