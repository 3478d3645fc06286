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

/// Seeds of `araim_server` (issue 12): ARAIM epochs over the ISM the target
/// puts in force (GPS and Galileo 1-6), a fault, ISM frames good and bad.
fn araim_seeds() {
    use raim_proto::araim_msg::{AraimCommandRef, IsmFrameRef, IsmSat, WireAraimConfig};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus/araim_server");
    std::fs::create_dir_all(&dir).expect("corpus dir");
    let ids: Vec<SatId> = (0..12u8).map(|i| SatId::new(if i % 2 == 0 { System::Gps } else { System::Galileo }, i / 2 + 1)).collect();
    let epoch: Vec<LinearObservation> = ids
        .iter()
        .enumerate()
        .map(|(i, &id)| LinearObservation::from_az_el(id, i as f64 * 2.4, 0.2 + (i as f64 * 0.5) % 1.3, 0.05 * i as f64 - 0.3))
        .collect();
    let mut faulted = epoch.clone();
    faulted[3].residual_m += 80.0;
    let ism: Vec<IsmSat> = ids.iter().map(|&id| IsmSat { id, sigma_ura_m: 0.75, sigma_ure_m: 0.5, b_nom_m: 0.5, p_sat: 1e-5 }).collect();
    let mut bad = ism.clone();
    bad[2].p_sat = 1.0;
    let mut p_const = [None; 5];
    p_const[System::Gps.index()] = Some(1e-4);
    p_const[System::Galileo.index()] = Some(1e-4);
    let ism_cmd = |seq, sats: &[IsmSat]| frame(&RequestRef { seq, command: CommandRef::Araim(AraimCommandRef::Ism(IsmFrameRef { config: WireAraimConfig::default(), p_const, sats })) });
    let epoch_cmd = |seq, sats: &[LinearObservation]| frame(&RequestRef { seq, command: CommandRef::Araim(AraimCommandRef::Epoch { time_s: 1.0, sats }) });
    let seeds: Vec<(&str, Vec<u8>)> = vec![
        ("epoch12", epoch_cmd(1, &epoch)),
        ("faulted12", epoch_cmd(1, &faulted)),
        ("ism_then_epoch", [ism_cmd(1, &ism), epoch_cmd(2, &epoch)].concat()),
        ("bad_ism", ism_cmd(1, &bad)),
        ("lock_then_ism", [frame(&RequestRef { seq: 1, command: CommandRef::Lock }), ism_cmd(2, &ism)].concat()),
    ];
    for (name, bytes) in seeds {
        std::fs::write(dir.join(name), bytes).expect("write seed");
    }
}
