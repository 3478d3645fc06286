//! ARAIM over the wire, shared by `qemu_araim.rs` and the
//! `qemu_araim_bench` example: the App. D vector and a 20-satellite sky as
//! ISM + linearised epochs, and a twin that sends every request to the
//! firmware under QEMU and to a host `Server` and checks that the two
//! answers are the same bytes.
#![allow(dead_code)]

use raim_core::measurement::MAX_SYSTEMS;
use raim_core::{LinearObservation, SatId, System};
use raim_proto::araim_msg::{AraimCommandRef, IsmFrameRef, IsmSat, WireAraimConfig};
use raim_proto::frame::FrameReceiver;
use raim_proto::message::{CommandRef, Response};
use raim_qemu::QemuSession;
use raim_server::{NoPlatform, Server};
use serde_json::Value;

/// One ARAIM scenario: the ISM frame's content and an epoch.
pub struct Scenario {
    pub config: WireAraimConfig,
    pub p_const: [Option<f64>; MAX_SYSTEMS],
    pub ism: Vec<IsmSat>,
    pub obs: Vec<LinearObservation>,
}

impl Scenario {
    pub fn ism_command(&self) -> CommandRef<'_> {
        CommandRef::Araim(AraimCommandRef::Ism(IsmFrameRef {
            config: self.config,
            p_const: self.p_const,
            sats: &self.ism,
        }))
    }
}

pub fn epoch_command(time_s: f64, sats: &[LinearObservation]) -> CommandRef<'_> {
    CommandRef::Araim(AraimCommandRef::Epoch { time_s, sats })
}

/// The ISM of ADD v3.0 App. D: sigma_URA 0.75 m, sigma_URE 0.5 m (with
/// the elevation model they give all ten published C_int, C_acc to
/// 1e-4 m^2: `raim_core::araim::error_model` tests), b_nom and P_sat of
/// the vector; the epoch's line of sight is minus the G row.
pub fn appendix_d() -> (Scenario, Value) {
    let text = std::fs::read_to_string(host_tests::vector_path("add_v3_appendix_d.json")).unwrap();
    let v: Value = serde_json::from_str(&text).unwrap();
    let c = &v["araim_config"];
    let f = |o: &Value, k: &str| o[k].as_f64().unwrap_or_else(|| panic!("{k}"));
    let config = WireAraimConfig {
        phmi_vert: f(c, "phmi_vert"),
        phmi_hor: f(c, "phmi_hor"),
        pfa_vert: f(c, "pfa_vert"),
        pfa_hor: f(c, "pfa_hor"),
        p_thres: f(c, "p_thres"),
        p_emt: f(c, "p_emt"),
        val_m: f(c, "val_m"),
        hal_m: f(c, "hal_m"),
        tol_pl_m: f(c, "tol_pl_m"),
        ..WireAraimConfig::default()
    };
    let mut p_const = [None; MAX_SYSTEMS];
    for (letter, p) in v["ism"]["p_const"].as_object().unwrap() {
        let s = System::from_letter(letter.chars().next().unwrap()).unwrap();
        p_const[s.index()] = p.as_f64();
    }
    let mut ism = Vec::new();
    let mut obs = Vec::new();
    for s in v["sats"].as_array().unwrap() {
        let id = SatId::new(
            System::from_letter(s["sys"].as_str().unwrap().chars().next().unwrap()).unwrap(),
            s["prn"].as_u64().unwrap() as u8,
        );
        let g: Vec<f64> = s["g_enu"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        ism.push(IsmSat {
            id,
            sigma_ura_m: 0.75,
            sigma_ure_m: 0.5,
            b_nom_m: f(s, "b_nom_m"),
            p_sat: f(s, "p_sat"),
        });
        obs.push(LinearObservation {
            id,
            los_enu: [-g[0], -g[1], -g[2]],
            residual_m: f(s, "residual_m"),
            sigma_m: None,
        });
    }
    let expected = v["expected"].clone();
    (
        Scenario {
            config,
            p_const,
            ism,
            obs,
        },
        expected,
    )
}

/// G10 + E10 spread over the sky (azimuth 137.5 deg apart, elevations 10
/// to 85 deg), ISM entries sigma_URA 0.75 m, sigma_URE 0.5 m, b_nom 0.5 m,
/// P_sat 1e-5, P_const 1e-4, residuals within +-0.15 m, plus `fault_m` on
/// satellite `faulty` (none when out of range).
pub fn sky20(faulty: usize, fault_m: f64) -> Scenario {
    sky(20, faulty, fault_m)
}

/// [`sky20`] with `n` satellites (GPS and Galileo alternating).
pub fn sky(n: usize, faulty: usize, fault_m: f64) -> Scenario {
    let mut p_const = [None; MAX_SYSTEMS];
    p_const[System::Gps.index()] = Some(1e-4);
    p_const[System::Galileo.index()] = Some(1e-4);
    let mut ism = Vec::new();
    let mut obs = Vec::new();
    for i in 0..n {
        let system = if i % 2 == 0 {
            System::Gps
        } else {
            System::Galileo
        };
        let id = SatId::new(system, (i / 2) as u8 + 1);
        let az = (i as f64 * 137.5) % 360.0;
        let el = 10.0 + (i as f64 * 29.0) % 75.0;
        let r = 0.3 * (((i * 7919) % 11) as f64 / 11.0 - 0.5);
        let f = if i == faulty { fault_m } else { 0.0 };
        obs.push(LinearObservation::from_az_el(
            id,
            az.to_radians(),
            el.to_radians(),
            r + f,
        ));
        ism.push(IsmSat {
            id,
            sigma_ura_m: 0.75,
            sigma_ure_m: 0.5,
            b_nom_m: 0.5,
            p_sat: 1e-5,
        });
    }
    Scenario {
        config: WireAraimConfig::default(),
        p_const,
        ism,
        obs,
    }
}

/// postcard bytes of a response: the bit-exact comparison (NaN included).
pub fn response_bytes(r: &Response) -> Vec<u8> {
    let mut buf = vec![0u8; raim_proto::MAX_RESPONSE_PAYLOAD];
    postcard::to_slice(r, &mut buf).unwrap().to_vec()
}

struct Sink(Vec<u8>);
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

/// The firmware under QEMU and a host `Server` (same crate, same code,
/// the host's `raim_core::Stat`), fed the same frames.
pub struct Twin {
    pub fw: QemuSession,
    pub host: Box<Server>,
    /// The host server's NMEA port since the last [`Twin::check_nmea`].
    pub host_nmea: Vec<u8>,
}

impl Twin {
    pub fn new(fw: QemuSession) -> Self {
        // The host reference set up as the session set the firmware up
        // (a bench host's runtime `Configure(Config::default())`).
        let mut host = Box::new(Server::new());
        host.take_runtime_config(raim_core::Config::default())
            .expect("the default configuration");
        Twin {
            fw,
            host,
            host_nmea: Vec::new(),
        }
    }

    /// The host server's answers to `bytes`.
    pub fn host_answers(&mut self, bytes: &[u8]) -> Vec<Response> {
        let (mut link, mut nmea) = (Sink(Vec::new()), Sink(Vec::new()));
        for &b in bytes {
            self.host
                .on_byte(b, &mut link, &mut nmea, &mut NoPlatform)
                .unwrap();
        }
        self.host_nmea.extend_from_slice(&nmea.0);
        let mut rx = Box::new(FrameReceiver::<{ raim_proto::MAX_RESPONSE_FRAME }>::new());
        link.0
            .iter()
            .filter_map(|&b| {
                rx.push(b)
                    .map(|p| postcard::from_bytes(p.unwrap()).unwrap())
            })
            .collect()
    }

    /// The firmware's NMEA sentences since the last check are the host
    /// server's, sentence for sentence (every ARAIM epoch writes its
    /// sentences); returns how many.
    pub fn check_nmea(&mut self) -> usize {
        let host = String::from_utf8(std::mem::take(&mut self.host_nmea)).unwrap();
        let host: Vec<&str> = host.lines().map(str::trim_end).collect();
        // The NMEA UART is read by its own thread: wait (boundedly) for it
        // to catch up with the answers already received.
        let mut fw = self.fw.drain_nmea();
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(5);
        while fw.len() < host.len() && std::time::Instant::now() < deadline {
            std::thread::sleep(std::time::Duration::from_millis(20));
            fw.extend(self.fw.drain_nmea());
        }
        let fw: Vec<&str> = fw.iter().map(|s| s.trim_end()).collect();
        assert_eq!(fw, host);
        fw.len()
    }

    /// Sends `command` to both; the firmware's answer must be the host's,
    /// byte for byte (body and configuration fingerprint).
    pub fn ask(&mut self, command: CommandRef<'_>, what: &str) -> Response {
        let (seq, bytes) = self.fw.frame(command).unwrap();
        self.fw.send_raw(&bytes).unwrap();
        let fw = self.fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
        let host = self.host_answers(&bytes);
        assert_eq!(host.len(), 1, "{what}: {host:?}");
        assert_eq!(fw.seq, Some(seq), "{what}: {fw:?}");
        assert_eq!(
            response_bytes(&fw),
            response_bytes(&host[0]),
            "{what}: firmware {fw:?}\nhost {:?}",
            host[0]
        );
        fw
    }
}

/// A pseudorange epoch (protocol 8, `AraimCommand::Ranges`) built from a
/// linearised scenario: a receiver at `RECEIVER_ECEF_M` (near ESBC), each
/// satellite on its scenario line of sight at 20,000-23,000 km, pseudorange
/// = geometric range + the constellation's receiver clock + the scenario
/// residual (fault included). The scenario's ISM applies unchanged.
pub const RECEIVER_ECEF_M: [f64; 3] = [3_582_105.0, 532_589.0, 5_232_755.0];
/// Receiver clock per system (m), `System::ALL` order.
pub const CLOCK_M: [f64; MAX_SYSTEMS] = [1_234.5, 1_240.25, 0.0, 0.0, 0.0];

pub fn ranges_of(s: &Scenario) -> Vec<raim_core::RangeObservation> {
    let g = raim_core::frames::ecef_to_geodetic(RECEIVER_ECEF_M);
    let r = raim_core::frames::enu_rotation(&g);
    s.obs
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let l = o.los_enu;
            let norm = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
            let range_m = 2.0e7 + 1.0e5 * i as f64;
            let u = raim_core::frames::unrotate(&r, [l[0] / norm, l[1] / norm, l[2] / norm]);
            raim_core::RangeObservation {
                id: o.id,
                pseudorange_m: range_m + CLOCK_M[o.id.system.index()] + o.residual_m,
                position_m: [
                    RECEIVER_ECEF_M[0] + range_m * u[0],
                    RECEIVER_ECEF_M[1] + range_m * u[1],
                    RECEIVER_ECEF_M[2] + range_m * u[2],
                ],
                sigma_m: o.sigma_m,
            }
        })
        .collect()
}

pub fn ranges_command(time_s: f64, sats: &[raim_core::RangeObservation]) -> CommandRef<'_> {
    CommandRef::Araim(AraimCommandRef::Ranges {
        time_s,
        apriori_m: None,
        sats,
    })
}
