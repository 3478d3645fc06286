//! Wire paths the message tests leave out (issue 37, structural
//! coverage, second pass): the model check's refusals on the wire, the
//! ARAIM result of a build that does not attempt exclusion and of either
//! PL output, the NMEA results of an epoch larger than their lists, the
//! boot counter's region read-back and its reserved value, and the geoid
//! and link receiver on inputs the other tests do not send.
extern crate std;

use std::vec::Vec;

use raim_core::araim::{
    AraimConfig, Exclusion, FdeLimits, Ism, Monitor, PlOutput, SatIsm, SatelliteModels,
};
use raim_core::consistency::{ModelCheck, ModelCheckConfig, ModelCheckError};
use raim_core::measurement::MAX_SYSTEMS;
use raim_core::{Decision, LinearObservation, SatId, System};

use crate::araim_msg::{AraimSummary, WireAraimResult, WireFde};
use crate::boot_counter::{self, BootCounterError, CounterFlash, FlashFault, ERASED};
use crate::error::WireError;
use crate::link::{LinkEvent, LinkReceiver};
use crate::result::WireResult;
use crate::CAPACITY;

/// Each refusal of the core's model check (`raim_core::consistency`,
/// docs/MODEL_CHECK.md) reaches the wire as a typed error carrying the
/// offending values: the window against the capacity, a sample's degrees
/// of freedom (0, or above `MAX_DOF` = 200), a time that does not
/// increase, and a fit without redundancy (n satellites for m unknowns
/// need m + 1).
///
/// Verifies: WIRE-InvalidDof, WIRE-TimeNotIncreasing
#[test]
fn model_check_refusals_keep_their_values_on_the_wire() {
    let cfg = ModelCheckConfig::DEFAULT;
    let mut mc = ModelCheck::<8>::new();
    let wide = ModelCheckConfig { window: 9, ..cfg };
    let e = mc.offer(&wide, 10.0, 1.0, 4).unwrap_err();
    assert_eq!(
        e,
        ModelCheckError::WindowOutOfRange {
            window: 9,
            capacity: 8
        }
    );
    assert!(matches!(
        WireError::from(e),
        WireError::OutOfRange { field, value, min, max }
            if field.as_str() == "window" && value == 9.0 && min == 1.0 && max == 8.0
    ));

    let e = mc.offer(&cfg, 10.0, 1.0, 0).unwrap_err();
    assert_eq!(e, ModelCheckError::ZeroDof);
    assert_eq!(
        WireError::from(e),
        WireError::InvalidDof { dof: 0, max: 200 }
    );
    let e = mc.offer(&cfg, 10.0, 1.0, 201).unwrap_err();
    assert_eq!(
        WireError::from(e),
        WireError::InvalidDof { dof: 201, max: 200 }
    );

    assert!(mc.offer(&cfg, 10.0, 1.0, 4).is_ok());
    let e = mc.offer(&cfg, 9.5, 1.0, 4).unwrap_err();
    assert_eq!(
        WireError::from(e),
        WireError::TimeNotIncreasing {
            previous_s: 10.0,
            now_s: 9.5
        }
    );

    assert_eq!(
        WireError::from(ModelCheckError::Geometry { n: 4, m: 4 }),
        WireError::TooFewSatellites { have: 4, need: 5 }
    );
}

/// The ISM entries of the ARAIM tests' sky (raim-server araim.rs): every
/// satellite sigma_URA 0.75 m, sigma_URE 0.5 m, b_nom 0.5 m, P_sat 1e-5.
struct Models;

impl SatelliteModels for Models {
    fn ism(&self, id: SatId) -> Option<SatIsm> {
        Some(SatIsm {
            id,
            sigma_ura_m: 0.75,
            sigma_ure_m: 0.5,
            b_nom_m: 0.5,
            p_sat: 1e-5,
        })
    }
}

/// Ten GPS and ten Galileo satellites spread over the sky (the layout of
/// raim-server's ARAIM tests), small residuals, plus `fault_m` on
/// satellite `faulty`.
fn sky20(faulty: usize, fault_m: f64) -> Vec<LinearObservation> {
    (0..20)
        .map(|i| {
            let system = if i % 2 == 0 {
                System::Gps
            } else {
                System::Galileo
            };
            let az = (i as f64 * 137.5) % 360.0;
            let el = 10.0 + (i as f64 * 29.0) % 75.0;
            let r = 0.3 * (((i * 7919) % 11) as f64 / 11.0 - 0.5);
            let f = if i == faulty { fault_m } else { 0.0 };
            LinearObservation::from_az_el(
                SatId::new(system, (i / 2) as u8 + 1),
                az.to_radians(),
                el.to_radians(),
                r + f,
            )
        })
        .collect()
}

fn p_const() -> Ism {
    let mut p = [None; MAX_SYSTEMS];
    p[System::Gps.index()] = Some(1e-4);
    p[System::Galileo.index()] = Some(1e-4);
    Ism { p_const: p }
}

type Engine = Monitor<f64, 24, 48>;

/// Runs `f` on a thread with room for the monitor (its mode tables are
/// large for a test thread's default stack in a debug build).
fn with_engine<R: Send + 'static>(f: fn(&mut Engine) -> R) -> R {
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(move || f(&mut std::boxed::Box::new(Engine::new())))
        .and_then(|h| h.join().map_err(|_| std::io::Error::other("panicked")))
        .unwrap()
}

/// A failed all-in-view test with more monitored modes than the build
/// attempts exclusion for (`FdeLimits::max_modes`) is an alarm with no
/// exclusion attempted; on the wire `NotAttempted` carries the count of
/// modes: 22 for this sky (20 single-satellite faults and the two
/// constellations, ADD v4 §2.3), and no N* since no FDE ran. One mode
/// more in the limit and the exclusion is attempted.
#[test]
fn a_failed_test_above_the_mode_limit_is_an_alarm_without_exclusion() {
    let (at_21, at_22) = with_engine(|m| {
        let cfg = AraimConfig::default();
        let obs = sky20(3, 100.0);
        let mut run = |max_modes| {
            let limits = FdeLimits {
                max_modes,
                work_candidate_modes: 110_000,
            };
            let v = m.linear(&cfg, &p_const(), &Models, &obs, limits).unwrap();
            assert!(!m.all_in_view().detection_passed);
            (
                v.exclusion,
                WireAraimResult::from_verdict(m.runs(), &v, &cfg, 7.0).unwrap(),
            )
        };
        (run(21), run(22))
    });
    let (exclusion, wire) = at_21;
    assert_eq!(exclusion, Exclusion::NotAttempted { monitored: 22 });
    assert_eq!(wire.fde, WireFde::NotAttempted { modes: 22 });
    assert_eq!(wire.all_in_view.monitored, 22);
    assert_eq!(wire.decision, Decision::Alarm);
    assert_eq!(wire.n_star_vertical, None);
    assert!(wire.excluded.is_empty());
    assert_eq!(wire.after_exclusion, None);
    assert_eq!(wire.time_s, 7.0);
    let (exclusion, wire) = at_22;
    assert!(matches!(exclusion, Exclusion::Fde(_)), "{exclusion:?}");
    assert!(!matches!(wire.fde, WireFde::NotAttempted { .. }));
}

/// The PLs that feed the availability are the configured output's
/// (`PlOutput`): the ADD's bracket end, never below the exact root and
/// less than TOL_PL (0.05 m) above it (SPEC §9.1), or the exact root
/// itself; the exact roots are reported either way.
#[test]
fn the_summary_reports_the_configured_pl_output() {
    let (add, exact) = with_engine(|m| {
        let mut run = |pl_output| {
            let cfg = AraimConfig {
                pl_output,
                ..AraimConfig::default()
            };
            let limits = FdeLimits {
                max_modes: 48,
                work_candidate_modes: 110_000,
            };
            let v = m
                .linear(&cfg, &p_const(), &Models, &sky20(usize::MAX, 0.0), limits)
                .unwrap();
            assert!(m.all_in_view().detection_passed);
            WireAraimResult::from_verdict(m.runs(), &v, &cfg, 0.0)
                .unwrap()
                .all_in_view
        };
        (run(PlOutput::AddBracket), run(PlOutput::Exact))
    });
    let check = |s: &AraimSummary| {
        assert!(s.vpl_exact_m.is_finite() && s.vpl_exact_m > 0.0, "{s:?}");
        assert!(s.hpl_exact_m.is_finite() && s.hpl_exact_m > 0.0, "{s:?}");
    };
    check(&add);
    check(&exact);
    assert_eq!(add.vpl_exact_m, exact.vpl_exact_m);
    assert!(add.vpl_m >= add.vpl_exact_m && add.vpl_m < add.vpl_exact_m + 0.05);
    assert!(add.hpl_m >= add.hpl_exact_m && add.hpl_m < add.hpl_exact_m + 0.05);
    assert_ne!(add.vpl_m, add.vpl_exact_m);
    assert_eq!(exact.vpl_m, exact.vpl_exact_m);
    assert_eq!(exact.hpl_m, exact.hpl_exact_m);
}

/// An ARAIM or particle-filter answer for more satellites than the NMEA
/// result holds keeps the first `CAPACITY` (the epoch's own list is of
/// that capacity, so this is a caller's list longer than any epoch), and
/// at most `MAX_EXCLUSIONS` (4) of the excluded ones are named.
#[test]
fn nmea_results_keep_their_capacity() {
    let ids: Vec<SatId> = (0..CAPACITY + 3)
        .map(|i| SatId::new(System::ALL[i % 5], (i / 5) as u8 + 1))
        .collect();
    let mut excluded = heapless::Vec::new();
    for id in ids.iter().take(6) {
        excluded.push(*id).unwrap();
    }
    let araim = WireAraimResult {
        time_s: 5.0,
        decision: Decision::Excluded,
        all_in_view: AraimSummary::default(),
        fde: WireFde::NoCandidate,
        excluded,
        after_exclusion: None,
        n_star_vertical: None,
        position_ecef_m: None,
    };
    let mut w = WireResult::empty();
    w.set_from_araim(&araim, ids.iter().copied());
    assert_eq!(w.satellites.len(), CAPACITY);
    assert_eq!(w.satellites.iter().filter(|s| !s.used).count(), 6);
    let named: Vec<(SatId, usize)> = w.exclusions.iter().map(|x| (x.id, x.index)).collect();
    let first4: Vec<(SatId, usize)> = ids.iter().copied().zip(0..).take(4).collect();
    assert_eq!(named, first4);

    let pf = crate::pf_msg::WirePfResult {
        time_s: 6.0,
        position_ecef_m: None,
        clock_m: [0.0; MAX_SYSTEMS],
        drift_m_s: 0.0,
        decision: 0.0,
        threshold: 1.0,
        alarm: false,
        isolated: None,
        excluded: ids.last().copied(),
        n_eff: 1.0,
        n_eff_before_ga: 1.0,
        used: 0,
        main_collapsed: false,
        aux_collapsed: 0,
        clock_jump: false,
        llr: heapless::Vec::new(),
    };
    w.set_from_pf(&pf, Decision::Ok, ids.iter().copied());
    assert_eq!(w.satellites.len(), CAPACITY);
    assert!(w.satellites.iter().all(|s| s.used));
    assert!(w.exclusions.is_empty());
}

/// GBS field 5 names the identified satellite; an identified satellite
/// missing from the list falls back to the best-scoring identifiable one
/// (none here: ARAIM's satellites carry no score).
#[test]
fn an_identified_satellite_outside_the_list_is_not_named() {
    let mut w = WireResult::empty();
    let araim = WireAraimResult {
        time_s: 5.0,
        decision: Decision::Ok,
        all_in_view: AraimSummary::default(),
        fde: WireFde::NoFault,
        excluded: heapless::Vec::new(),
        after_exclusion: None,
        n_star_vertical: None,
        position_ecef_m: None,
    };
    let ids = [SatId::new(System::Gps, 1), SatId::new(System::Gps, 2)];
    w.set_from_araim(&araim, ids);
    w.identified = Some(ids[1]);
    assert_eq!(w.most_likely_failed().map(|s| s.id), Some(ids[1]));
    w.identified = Some(SatId::new(System::Galileo, 9));
    assert_eq!(w.most_likely_failed(), None);
}

/// A flash model: two pages of `words` words, erased to all ones, a
/// program clears bits. `decay_after` reads of a programmed word return
/// it; later reads return it with bit 0 flipped (a cell that passes the
/// read-back and then loses its charge).
struct Flash {
    words: usize,
    cells: [Vec<u32>; 2],
    reads: [Vec<usize>; 2],
    decay_after: Option<usize>,
}

impl Flash {
    fn new(words: usize, decay_after: Option<usize>) -> Self {
        Flash {
            words,
            cells: [std::vec![ERASED; words], std::vec![ERASED; words]],
            reads: [std::vec![0; words], std::vec![0; words]],
            decay_after,
        }
    }
}

impl CounterFlash for Flash {
    fn page_words(&self) -> usize {
        self.words
    }
    fn read(&mut self, page: usize, word: usize) -> Result<u32, FlashFault> {
        let v = *self.cells[page].get(word).ok_or(FlashFault)?;
        let n = &mut self.reads[page][word];
        *n += 1;
        Ok(match self.decay_after {
            Some(k) if v != ERASED && *n > k => v ^ 1,
            _ => v,
        })
    }
    fn erase(&mut self, page: usize) -> Result<(), FlashFault> {
        self.cells[page].fill(ERASED);
        self.reads[page].fill(0);
        Ok(())
    }
    fn program(&mut self, page: usize, word: usize, value: u32) -> Result<(), FlashFault> {
        let c = self.cells[page].get_mut(word).ok_or(FlashFault)?;
        *c &= value;
        self.reads[page][word] = 0;
        Ok(())
    }
}

/// A written entry that passes its `READS` (3) read-backs and then reads
/// wrong when the region is scanned again is a failed boot: after
/// `ATTEMPTS` (3) writes the boot has no value, `Verify` with the value
/// written (1, the region was empty) and the one read (0: no whole entry).
///
/// Verifies: SAFE-BOOT-COUNTER
#[test]
fn an_entry_lost_after_its_read_back_fails_the_boot() {
    let mut f = Flash::new(8, Some(boot_counter::READS));
    assert_eq!(
        boot_counter::advance(&mut f),
        Err(BootCounterError::Verify {
            expected: 1,
            read: 0
        })
    );
    let mut steady = Flash::new(8, None);
    assert_eq!(boot_counter::advance(&mut steady), Ok(1));
    assert_eq!(boot_counter::advance(&mut steady), Ok(2));
}

/// `[v, !v]` with v = u32::MAX (and so !v = 0) is no entry: values are
/// 1..u32::MAX, all ones is the erased state (the module's layout); such
/// a pair alone leaves the region at 0.
#[test]
fn the_erased_value_is_no_entry() {
    let mut f = Flash::new(8, None);
    f.cells[0][1] = 0;
    assert_eq!(boot_counter::value(&mut f), Ok(0));
    f.cells[1][2] = 7;
    f.cells[1][3] = !7;
    assert_eq!(boot_counter::value(&mut f), Ok(7));
}

/// The geoid separation of a non-finite longitude (or latitude) is
/// undefined.
#[test]
fn the_geoid_needs_a_finite_position() {
    use crate::nmea::geoid::separation_m;
    assert_eq!(separation_m(0.5, f64::NAN), None);
    assert_eq!(separation_m(f64::INFINITY, 0.5), None);
    assert!(separation_m(0.5, 0.5).is_some());
}

/// The events of `bytes` pushed into `rx` (each `push`, then `poll`
/// until `None`): `Ok(payload)` for a verified frame, `Err(())` for a
/// framing error. No RTCM frame is sent in these tests.
fn events<const B: usize>(rx: &mut LinkReceiver<B>, bytes: &[u8]) -> Vec<Result<Vec<u8>, ()>> {
    fn owned(ev: LinkEvent<'_>) -> Result<Vec<u8>, ()> {
        match ev {
            LinkEvent::Frame(Ok(p)) => Ok(p.to_vec()),
            _ => Err(()),
        }
    }
    let mut out = Vec::new();
    for &b in bytes {
        let mut ev = rx.push(b).map(owned);
        while let Some(e) = ev {
            out.push(e);
            ev = rx.poll().map(owned);
        }
    }
    out
}

/// A status request's frame and its payload.
fn status_frame(seq: u32) -> (Vec<u8>, Vec<u8>) {
    use crate::message::{CommandRef, RequestRef};
    let req = RequestRef {
        seq,
        command: CommandRef::Status,
    };
    let mut scratch = [0u8; 256];
    let mut out = [0u8; 256];
    let frame = crate::frame::encode(&req, &mut scratch, &mut out)
        .unwrap()
        .to_vec();
    let payload = postcard::to_slice(&req, &mut scratch).unwrap().to_vec();
    (frame, payload)
}

/// An RTCM candidate `D3 00 0A` (10 payload bytes declared, 16 in all)
/// whose CRC-24Q fails (the three CRC bytes 0x22 are not the CRC of the
/// 0x11 payload): not RTCM. Its replay gives a framing error at the
/// header's zero, and its last 14 bytes are the open tail, closed as a
/// second framing error (module documentation of `link`).
fn failed_candidate() -> Vec<u8> {
    let mut c = std::vec![0xD3, 0x00, 0x0A];
    c.extend_from_slice(&[0x11; 10]);
    c.extend_from_slice(&[0x22; 3]);
    c
}

/// A candidate that fails its CRC with no zero in the last 204 of its
/// bytes, replayed into a COBS receiver of 64 bytes: the replay
/// overflows it (one `Overflow` error after the header's one), so no
/// tail is left open; the receiver skips to the next delimiter and the
/// request after it comes out whole.
#[test]
fn a_candidate_that_overflows_the_cobs_receiver_leaves_no_tail() {
    let mut rx = LinkReceiver::<64>::new();
    let mut bytes = std::vec![0xD3, 0x00, 0xC8];
    bytes.extend_from_slice(&[0x55; 203]);
    let (frame, payload) = status_frame(3);
    bytes.push(0);
    bytes.extend_from_slice(&frame);
    assert_eq!(events(&mut rx, &bytes), [Err(()), Err(()), Ok(payload)]);
    assert_eq!(rx.counts().rtcm_bad_crc, 1);
}

/// After a closed tail, a chunk that overflows the COBS receiver (65
/// bytes in 64) is reported once and joins nothing; the request after
/// the next delimiter comes out whole.
#[test]
fn an_overflowing_chunk_after_a_closed_tail_joins_nothing() {
    let mut rx = LinkReceiver::<64>::new();
    let mut bytes = failed_candidate();
    bytes.extend_from_slice(&[0x33; 70]);
    bytes.push(0);
    let (frame, payload) = status_frame(4);
    bytes.extend_from_slice(&frame);
    assert_eq!(
        events(&mut rx, &bytes),
        [Err(()), Err(()), Err(()), Ok(payload)]
    );
}

/// A joined chunk longer than `RTCM_MAX_FRAME` (1029 bytes: the 14-byte
/// tail and 1,015 more before the delimiter) is not tried: only the
/// chunk's own error is reported, and the next request comes out whole.
#[test]
fn a_joined_chunk_longer_than_an_rtcm_frame_is_not_tried() {
    let mut rx = LinkReceiver::<2048>::new();
    let mut bytes = failed_candidate();
    bytes.extend_from_slice(&[0x33; 1015]);
    bytes.push(0);
    let (frame, payload) = status_frame(5);
    bytes.extend_from_slice(&frame);
    assert_eq!(
        events(&mut rx, &bytes),
        [Err(()), Err(()), Err(()), Ok(payload)]
    );
}

/// Pseudorange lines of sight are seen from the result's position: six
/// GPS satellites 2e7 m above a receiver on the equator, pushed sideways,
/// have DOPs from there; a position that is not a number gives no frame
/// to see them from, so no DOPs (the sentences leave them empty).
#[test]
fn dops_need_a_finite_position() {
    use crate::nmea::{dops, Sky};
    use raim_core::{Epoch, RangeObservation};
    let rx = [6_378_137.0, 0.0, 0.0];
    let sats: Vec<RangeObservation> = [
        (0.0, 0.0),
        (1.2e7, 0.3e7),
        (-1.0e7, 0.8e7),
        (0.2e7, -1.1e7),
        (0.9e7, 0.9e7),
        (-0.7e7, -0.6e7),
    ]
    .iter()
    .enumerate()
    .map(|(k, &(e, n))| RangeObservation {
        id: SatId::new(System::Gps, k as u8 + 1),
        pseudorange_m: 2.2e7,
        position_m: [rx[0] + 2.0e7, e, n],
        sigma_m: None,
    })
    .collect();
    let epoch = Epoch::ranges(1e9, &sats, None);
    let sky = Sky::new(&epoch);
    let result = |position_ecef_m| {
        let araim = WireAraimResult {
            time_s: 1e9,
            decision: Decision::Ok,
            all_in_view: AraimSummary::default(),
            fde: WireFde::NoFault,
            excluded: heapless::Vec::new(),
            after_exclusion: None,
            n_star_vertical: None,
            position_ecef_m,
        };
        let mut w = WireResult::empty();
        w.set_from_araim(&araim, sats.iter().map(|s| s.id));
        w
    };
    let d = dops(&result(Some(rx)), &sky).unwrap();
    assert!(d.pdop.is_finite() && d.pdop >= d.hdop && d.pdop >= d.vdop && d.hdop > 0.0);
    assert_eq!(dops(&result(Some([f64::NAN, 0.0, 0.0])), &sky), None);
    assert_eq!(dops(&result(None), &sky), None);
}
