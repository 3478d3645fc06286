//! A digest of the host `Server`'s ARAIM answers: the postcard bytes of
//! every response (results and typed errors) to a fixed set of ISM frames
//! and epochs (ADD v3.0 App. D; the 20-, 24- and 32-satellite skies of
//! `qemu_common/araim.rs`, clean, with single and pair faults, and at
//! P_sat 1e-3 beyond the mode capacity; the same skies as pseudorange
//! epochs, with and without a given sigma; and refused epochs). A change
//! to the ARAIM decision path that is meant to be bit for bit leaves the
//! digest unchanged; one line per answer is printed for a diff.
//!
//! `cargo run --release -p host-tests --example araim_digest`

#[path = "../tests/qemu_common/araim.rs"]
mod araim_common;

use araim_common::{
    appendix_d, epoch_command, ranges_command, ranges_of, response_bytes, sky, sky20, Scenario,
};
use raim_core::SatId;
use raim_proto::frame::{encode, FrameReceiver};
use raim_proto::message::{CommandRef, RequestRef, Response};
use raim_server::{NoPlatform, Server};

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

struct Host {
    server: Box<Server>,
    seq: u32,
    digest: u64,
    answers: usize,
}

impl Host {
    fn ask(&mut self, command: CommandRef<'_>, what: &str) {
        let mut scratch = vec![0u8; 16384];
        let mut out = vec![0u8; 16384];
        let bytes = encode(
            &RequestRef {
                seq: self.seq,
                command,
            },
            &mut scratch,
            &mut out,
        )
        .unwrap()
        .to_vec();
        self.seq += 1;
        let (mut link, mut nmea) = (Sink(Vec::new()), Sink(Vec::new()));
        for &b in &bytes {
            self.server
                .on_byte(b, &mut link, &mut nmea, &mut NoPlatform)
                .unwrap();
        }
        let mut rx = Box::new(FrameReceiver::<{ raim_proto::MAX_RESPONSE_FRAME }>::new());
        let responses: Vec<Response> = link
            .0
            .iter()
            .filter_map(|&b| {
                rx.push(b)
                    .map(|p| postcard::from_bytes(p.unwrap()).unwrap())
            })
            .collect();
        assert_eq!(responses.len(), 1, "{what}");
        let r = &responses[0];
        let body = response_bytes(r);
        // FNV-1a over the answer bytes, chained.
        let mut h = self.digest;
        for b in &body {
            h ^= u64::from(*b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        self.digest = h;
        self.answers += 1;
        let mut line = 0xcbf2_9ce4_8422_2325u64;
        for b in &body {
            line ^= u64::from(*b);
            line = line.wrapping_mul(0x0100_0000_01b3);
        }
        println!("{what}: {line:016x} {:?}", r.body);
    }

    fn scenario(&mut self, s: &Scenario, what: &str) {
        self.ask(s.ism_command(), &format!("{what} ISM"));
        self.ask(epoch_command(1.0, &s.obs), &format!("{what} linear"));
        let ranges = ranges_of(s);
        self.ask(ranges_command(2.0, &ranges), &format!("{what} ranges"));
    }
}

fn main() {
    let mut server = Box::new(Server::new());
    server
        .take_runtime_config(raim_core::Config::default())
        .expect("the default configuration");
    let mut h = Host {
        server,
        seq: 0,
        digest: 0xcbf2_9ce4_8422_2325,
        answers: 0,
    };
    let (d, _) = appendix_d();
    h.ask(epoch_command(0.0, &d.obs), "no ISM");
    h.scenario(&d, "App. D");
    let mut faulted = appendix_d().0;
    faulted.obs[2].residual_m += 30.0;
    h.scenario(&faulted, "App. D, 30 m on sat 2");
    h.scenario(&sky20(usize::MAX, 0.0), "sky20 clean");
    for faulty in 0..20 {
        h.scenario(&sky20(faulty, 100.0), &format!("sky20, 100 m on {faulty}"));
        h.scenario(&sky20(faulty, 12.0), &format!("sky20, 12 m on {faulty}"));
    }
    let mut given = sky20(3, 100.0);
    for (i, o) in given.obs.iter_mut().enumerate() {
        o.sigma_m = Some(0.3 + 0.05 * i as f64);
    }
    h.scenario(&given, "sky20 given sigma, 100 m on 3");
    h.scenario(&sky(24, 0, 100.0), "sky24, 100 m on 0");
    for n in [24, 32] {
        let mut pair = sky(n, 0, 100.0);
        pair.obs[n - 1].residual_m -= 100.0;
        h.scenario(&pair, &format!("sky{n}, pair"));
    }
    h.scenario(&sky(32, 0, 100.0), "sky32, 100 m on 0");
    let mut wide = sky(32, usize::MAX, 0.0);
    for s in wide.ism.iter_mut() {
        s.p_sat = 1e-3;
    }
    h.scenario(&wide, "sky32, P_sat 1e-3");
    // Refusals: not in the ISM, a NaN residual, a zero sigma, too few.
    let s = sky20(usize::MAX, 0.0);
    h.ask(s.ism_command(), "sky20 ISM again");
    let mut stranger = s.obs.clone();
    stranger[4].id = SatId::new(raim_core::System::Beidou, 7);
    h.ask(epoch_command(3.0, &stranger), "not in ISM");
    let mut nan = s.obs.clone();
    nan[1].residual_m = f64::NAN;
    h.ask(epoch_command(3.0, &nan), "NaN residual");
    let mut zero = s.obs.clone();
    zero[6].sigma_m = Some(0.0);
    h.ask(epoch_command(3.0, &zero), "zero sigma");
    h.ask(epoch_command(3.0, &s.obs[..3]), "too few");
    let mut bad_ranges = ranges_of(&s);
    bad_ranges[2].pseudorange_m = f64::INFINITY;
    h.ask(ranges_command(3.0, &bad_ranges), "infinite pseudorange");
    println!("{} answers, digest {:016x}", h.answers, h.digest);
}
