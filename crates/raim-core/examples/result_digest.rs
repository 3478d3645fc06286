//! Every field of 12,200 results (3,000 linearised and 1,000 pseudorange
//! epochs, random skies of 5-32 satellites in 1-3 constellations, 0-3
//! faults of 10-70 m, each rule; 1,500 of the linearised epochs also in
//! sequence through an engine with the MCUSUM on, 600 with the
//! reconstruction FDE; the f64 and the f32 engine), printed with
//! `Debug` (shortest round-trip floats: equal text is equal bits) into a
//! file, with its FNV-1a digest. Two builds whose digests agree give the
//! same results bit for bit (the speed work was checked this way
//! against the commit before it, BENCHMARKS.md):
//! `cargo run --release -p raim-core --example result_digest [FILE]`.
use raim_core::config::FiRule;
use raim_core::frames::{ecef_to_geodetic, enu_rotation, unrotate};
use raim_core::{Config, Epoch, LinearObservation, Raim, RangeObservation, SatId, System};
const RX: [f64; 3] = [-3_962_108.673, 3_381_309.574, 3_668_678.638];
struct Rng(u64);
impl Rng {
    fn u(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}
fn main() {
    let mut rng = Rng(0x9e3779b97f4a7c15);
    let rot = enu_rotation(&ecef_to_geodetic(RX));
    let mut out = String::new();
    // Engines that persist across the epochs: the MCUSUM on (its state and
    // holds carry over), and the reconstruction FDE.
    let mcusum_cfg = Config::default().split_false_alarm_budget(0.5);
    let recon_cfg = Config {
        fde_method: raim_core::config::FdeMethod::Reconstruction {
            t_max: 3,
            group_budget: 200,
        },
        ..Config::default()
    };
    let mut mcusum64 = Raim::<32, f64>::new();
    let mut mcusum32 = Raim::<32, f32>::new();
    for trial in 0..3000 {
        let n = 5 + trial % 28;
        let sys = [System::Gps, System::Galileo, System::Beidou];
        let nsys = 1 + trial % 3;
        let mut lin = Vec::new();
        let mut rng_obs = Vec::new();
        let nf = trial % 4;
        for i in 0..n {
            let az = rng.u() * std::f64::consts::TAU;
            let el = (5.0 + 85.0 * rng.u()).to_radians();
            let id = SatId::new(sys[i % nsys], i as u8 + 1);
            let mut f = 0.0;
            if i < nf {
                f = 10.0 + 60.0 * rng.u();
            }
            let noise = (rng.u() - 0.5) * 2.0;
            let mut o = LinearObservation::from_az_el(id, az, el, noise + f);
            if trial % 5 != 0 {
                o.sigma_m = Some(0.5 + 2.0 * rng.u());
            }
            lin.push(o);
            let d = unrotate(&rot, [el.cos() * az.sin(), el.cos() * az.cos(), el.sin()]);
            let rs = 26_560_000.0f64;
            let b: f64 = RX.iter().zip(d.iter()).map(|(p, q)| p * q).sum();
            let c = RX.iter().map(|p| p * p).sum::<f64>() - rs * rs;
            let range = -b + (b * b - c).sqrt();
            rng_obs.push(RangeObservation {
                id,
                pseudorange_m: range + 1000.0 * (i % nsys) as f64 + noise + f,
                position_m: [0, 1, 2].map(|k| RX[k] + range * d[k]),
                sigma_m: None,
            });
        }
        let rule = [FiRule::Mle, FiRule::LraimFlat, FiRule::default()][trial % 3];
        let cfg = Config {
            rule,
            ..Config::default()
        };
        let apriori = Some(RX.map(|v| v + 30.0));
        let e1 = Epoch::linear(trial as f64, &lin);
        let e2 = Epoch::ranges(trial as f64, &rng_obs, apriori);
        out += &format!(
            "{:?}\n{:?}\n",
            Raim::<32, f64>::new().process(&cfg, &e1),
            Raim::<32, f32>::new().process(&cfg, &e1)
        );
        if trial % 2 == 0 {
            // The MCUSUM engines see the linearised epochs in sequence.
            out += &format!(
                "{:?}\n{:?}\n",
                mcusum64.process(&mcusum_cfg, &e1),
                mcusum32.process(&mcusum_cfg, &e1)
            );
        }
        if trial % 5 == 1 {
            out += &format!(
                "{:?}\n{:?}\n",
                Raim::<32, f64>::new().process(&recon_cfg, &e1),
                Raim::<32, f32>::new().process(&recon_cfg, &e1)
            );
        }
        if trial % 3 == 0 {
            out += &format!(
                "{:?}\n{:?}\n",
                Raim::<32, f64>::new().process(&cfg, &e2),
                Raim::<32, f32>::new().process(&cfg, &e2)
            );
        }
    }
    let mut h: u64 = 0xcbf29ce484222325;
    for b in out.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    let ex = out.matches("Excluded").count();
    let al = out.matches("Alarm").count();
    println!(
        "{} bytes, fnv {h:016x}, Excluded {ex}, Alarm {al}",
        out.len()
    );
    std::fs::write(
        std::env::args()
            .nth(1)
            .unwrap_or("result_digest.txt".into()),
        out,
    )
    .unwrap();
}
