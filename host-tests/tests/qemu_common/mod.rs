//! Shared by the `qemu_*` tests: a firmware session, the host core's answer
//! in wire form, and synthetic pseudorange epochs.
#![allow(dead_code)]

use raim_core::frames::{geodetic_to_ecef, Geodetic};
use raim_core::{Config, Epoch, Raim, RaimError, RangeObservation, SatId, System};
use raim_proto::{WireResult, CAPACITY};
use raim_qemu::QemuSession;

/// A firmware session (builds the firmware once per test binary).
pub fn session() -> QemuSession {
    static ELF: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    let elf = ELF.get_or_init(|| raim_qemu::firmware_elf().expect("firmware build"));
    QemuSession::start(elf).expect("qemu-system-arm with the firmware")
}

/// A session on `machine` with its firmware build (the QEMU
/// tests that the machine supports run on both boards).
#[allow(dead_code)]
pub fn session_on(machine: raim_qemu::Machine) -> QemuSession {
    let elf = raim_qemu::firmware_elf_for(machine).expect("firmware build");
    QemuSession::start_with(
        &elf,
        &raim_qemu::Options {
            machine,
            ..raim_qemu::Options::default()
        },
    )
    .expect("qemu-system-arm with the firmware")
}

/// A session on `machine` with its streaming build
/// (`raim_qemu::firmware_elf_stream`: a 30 s pause on the link, so that a
/// loaded host's stall of QEMU does not cut a streamed frame).
#[allow(dead_code)]
pub fn stream_session_on(machine: raim_qemu::Machine) -> QemuSession {
    let elf = raim_qemu::firmware_elf_stream(machine).expect("firmware build");
    QemuSession::start_with(
        &elf,
        &raim_qemu::Options {
            machine,
            ..raim_qemu::Options::default()
        },
    )
    .expect("qemu-system-arm with the firmware")
}

/// The host core's result for an epoch, in wire form, in the firmware's
/// precision ([`raim_proto::DevicePrecision`]).
pub fn host_result(cfg: &Config, epoch: &Epoch<'_>) -> Result<WireResult, RaimError> {
    Raim::<CAPACITY, raim_proto::DevicePrecision>::new()
        .process(cfg, epoch)
        .map(|r| WireResult::from_result(&r))
}

/// postcard bytes: a bit-exact comparison that also covers NaN fields.
pub fn wire_bytes(r: &WireResult) -> Vec<u8> {
    let mut buf = vec![0u8; raim_proto::MAX_RESPONSE_PAYLOAD];
    postcard::to_slice(r, &mut buf).unwrap().to_vec()
}

/// A small deterministic generator (xorshift64*), for noise.
pub struct Rng(u64);
impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Standard normal (Box-Muller).
    pub fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform().max(1e-300), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

/// The receiver: the 0759 station of shared/data (its RINEX header's
/// approximate position).
pub const RECEIVER_ECEF_M: [f64; 3] = [-3_962_108.673, 3_381_309.574, 3_668_678.638];

/// Satellites at GPS orbit radius at the given azimuths/elevations (deg)
/// seen from the receiver, with pseudoranges = range + clock (1234.5 m) +
/// noise (sigma 1 m) + the given faults (index, m).
pub fn range_epoch(
    sky_deg: &[(f64, f64)],
    systems: &[System],
    rng: &mut Rng,
    faults: &[(usize, f64)],
) -> Vec<RangeObservation> {
    const ORBIT_RADIUS_M: f64 = 26_560_000.0;
    let rx = RECEIVER_ECEF_M;
    let g = raim_core::frames::ecef_to_geodetic(rx);
    let (sl, cl, so, co) = (
        g.lat_rad.sin(),
        g.lat_rad.cos(),
        g.lon_rad.sin(),
        g.lon_rad.cos(),
    );
    // Rows: east, north, up in ECEF.
    let r = [
        [-so, co, 0.0],
        [-sl * co, -sl * so, cl],
        [cl * co, cl * so, sl],
    ];
    let rx_norm = rx.iter().map(|v| v * v).sum::<f64>().sqrt();
    sky_deg
        .iter()
        .enumerate()
        .map(|(i, &(az, el))| {
            let (az, el) = (az.to_radians(), el.to_radians());
            let enu = [el.cos() * az.sin(), el.cos() * az.cos(), el.sin()];
            // ECEF unit line of sight = R^T enu.
            let los: Vec<f64> = (0..3)
                .map(|k| r[0][k] * enu[0] + r[1][k] * enu[1] + r[2][k] * enu[2])
                .collect();
            // Range d with |rx + d los| = orbit radius.
            let b = (0..3).map(|k| rx[k] * los[k]).sum::<f64>();
            let d = -b + (b * b - rx_norm * rx_norm + ORBIT_RADIUS_M * ORBIT_RADIUS_M).sqrt();
            let pos = [rx[0] + d * los[0], rx[1] + d * los[1], rx[2] + d * los[2]];
            let fault: f64 = faults.iter().filter(|f| f.0 == i).map(|f| f.1).sum();
            let system = systems[i % systems.len()];
            RangeObservation {
                id: SatId::new(system, i as u8 + 1),
                pseudorange_m: d + 1234.5 + rng.normal() + fault,
                position_m: pos,
                sigma_m: if i % 3 == 2 { None } else { Some(1.0) },
            }
        })
        .collect()
}

/// Pseudorange epochs: clean, one 60 m fault, two faults, GPS+Galileo,
/// with and without a-priori position, and an epoch at 2024-02-29 12:00 UTC.
pub fn range_vectors(seed: u64) -> Vec<(f64, Vec<RangeObservation>, Option<[f64; 3]>)> {
    let sky: Vec<(f64, f64)> = (0..12)
        .map(|i| (i as f64 * 31.0, 12.0 + (i as f64 * 23.0) % 70.0))
        .collect();
    let mut rng = Rng::new(seed);
    let apriori = Some(geodetic_to_ecef(Geodetic {
        lat_rad: 0.62,
        lon_rad: 2.43,
        height_m: 0.0,
    }));
    let t0 = 1_709_208_000.0;
    vec![
        (
            t0,
            range_epoch(&sky[..8], &[System::Gps], &mut rng, &[]),
            None,
        ),
        (
            t0 + 1.0,
            range_epoch(&sky[..9], &[System::Gps], &mut rng, &[(4, 60.0)]),
            apriori,
        ),
        (
            t0 + 2.0,
            range_epoch(&sky, &[System::Gps], &mut rng, &[(2, 80.0), (7, -70.0)]),
            apriori,
        ),
        (
            t0 + 3.0,
            range_epoch(
                &sky,
                &[System::Gps, System::Galileo],
                &mut rng,
                &[(5, 45.0)],
            ),
            None,
        ),
        (
            t0 + 4.0,
            range_epoch(&sky[..5], &[System::Gps], &mut rng, &[]),
            apriori,
        ),
        (
            t0 + 5.0,
            range_epoch(&sky[..4], &[System::Gps], &mut rng, &[]),
            apriori,
        ),
    ]
}

/// A byte sink for the host `Server`'s UARTs.
pub struct Sink(pub Vec<u8>);
impl embedded_io::ErrorType for Sink {
    type Error = core::convert::Infallible;
}
impl embedded_io::Write for Sink {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.0.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}
