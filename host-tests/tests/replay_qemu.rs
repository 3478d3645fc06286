//! `raim replay --target qemu`: real epochs (0759, the 50 m G24 step from
//! 00:20:00, and the ambiguous stretch; ESBC G+R+E+C with a step on a
//! GLONASS satellite) processed by the firmware under
//! QEMU give bit-for-bit the host core's results (postcard bytes of the
//! wire form, which also covers NaN fields).

mod replay_common;

use raim_core::{Epoch, Raim, System};
use raim_gnss::faults::FaultPlan;
use raim_gnss::ranging::{prepare_epoch, RangingOptions};
use raim_gnss::{time, NavData, ObsData};
use raim_proto::{WireResult, CAPACITY};
use replay_common::{data, geodetic_config};

fn bytes(r: &WireResult) -> Vec<u8> {
    let mut buf = vec![0u8; raim_proto::MAX_RESPONSE_PAYLOAD];
    postcard::to_slice(r, &mut buf).unwrap().to_vec()
}

/// Verifies: FW-EQUIV
#[test]
fn firmware_matches_host_on_real_epochs() {
    let obs = ObsData::load(&data("07590920.05o")).unwrap();
    let nav = NavData::load(&data("07590920.05n")).unwrap();
    let first = obs.epochs[0].time_gps_s;
    let plan = FaultPlan {
        faults: vec![FaultPlan::parse_cli("step:G24:50@00:20:00", first).unwrap()],
        seed: 0,
    };
    // Before/at the fault onset, and the ambiguous stretch (QEMU takes
    // ~0.3 s per epoch, so the window is short).
    let windows = [("00:19:30", "00:20:30"), ("00:38:30", "00:41:00")];
    let inside = |t: f64| {
        windows.iter().any(|(a, b)| {
            t >= time::resolve(a, first).unwrap() - 0.5
                && t <= time::resolve(b, first).unwrap() + 0.5
        })
    };
    let opts = RangingOptions {
        systems: vec![System::Gps],
        elevation_mask_rad: 15f64.to_radians(),
        ..Default::default()
    };
    let cfg = geodetic_config();
    let elf = raim_qemu::firmware_elf().expect("firmware build");
    let mut fw = raim_qemu::QemuSession::start(&elf).expect("qemu-system-arm with the firmware");
    fw.configure(&cfg).unwrap();
    let mut host = Raim::<CAPACITY, raim_proto::DevicePrecision>::new();
    let mut compared = 0;
    for e in obs.epochs.iter().filter(|e| inside(e.time_gps_s)) {
        let p = prepare_epoch(&nav, e, &opts, obs.approx_position_m);
        let mut sats = p.observations();
        plan.apply(e.time_gps_s, &mut sats);
        let epoch = Epoch::ranges(e.time_gps_s, &sats, p.reference_m);
        let h = WireResult::from_result(&host.process(&cfg, &epoch).unwrap());
        let f = fw.process(&epoch).unwrap().outcome.unwrap();
        assert_eq!(bytes(&h), bytes(&f), "{}", time::time_of_day(e.time_gps_s));
        compared += 1;
    }
    assert_eq!(compared, 9);
}

/// ESBC with G+R+E+C (29-32 satellites, four clock columns, GLONASS
/// satellites carrying their own sigmas) and a 30 m step on R02 from
/// 01:00:00: the firmware's results are the host's, bit for bit at the
/// device precision, on the 4 epochs 00:59:30-01:01:00.
#[test]
fn firmware_matches_host_with_glonass() {
    let obs = ObsData::load(&data("ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz")).unwrap();
    let nav = NavData::load(&data("ESBC00DNK_R_20201770000_01D_MN.rnx.gz")).unwrap();
    let first = obs.epochs[0].time_gps_s;
    let plan = FaultPlan {
        faults: vec![FaultPlan::parse_cli("step:R02:30@01:00:00", first).unwrap()],
        seed: 0,
    };
    let (t0, t1) = (
        time::resolve("00:59:30", first).unwrap(),
        time::resolve("01:01:00", first).unwrap(),
    );
    let cfg = geodetic_config();
    let mut glonass_sigma = cfg.sigma_model;
    glonass_sigma.ura_m = raim_gnss::glonass::glonass_ura_m(glonass_sigma.ura_m);
    let opts = RangingOptions {
        systems: vec![
            System::Gps,
            System::Glonass,
            System::Galileo,
            System::Beidou,
        ],
        glonass_sigma: Some(glonass_sigma),
        ..Default::default()
    };
    let elf = raim_qemu::firmware_elf().expect("firmware build");
    let mut fw = raim_qemu::QemuSession::start(&elf).expect("qemu-system-arm with the firmware");
    fw.configure(&cfg).unwrap();
    let mut host = Raim::<CAPACITY, raim_proto::DevicePrecision>::new();
    let mut compared = 0;
    let mut r02_excluded = 0;
    for e in obs
        .epochs
        .iter()
        .filter(|e| e.time_gps_s >= t0 - 0.5 && e.time_gps_s <= t1 + 0.5)
    {
        let p = prepare_epoch(&nav, e, &opts, obs.approx_position_m);
        let mut sats = p.observations();
        assert!(sats
            .iter()
            .any(|s| s.id.system == System::Glonass && s.sigma_m.is_some()));
        plan.apply(e.time_gps_s, &mut sats);
        let epoch = Epoch::ranges(e.time_gps_s, &sats, p.reference_m);
        let hr = host.process(&cfg, &epoch).unwrap();
        r02_excluded += usize::from(
            hr.exclusions
                .iter()
                .any(|x| x.id == raim_core::SatId::new(System::Glonass, 2)),
        );
        let h = WireResult::from_result(&hr);
        let f = fw.process(&epoch).unwrap().outcome.unwrap();
        assert_eq!(bytes(&h), bytes(&f), "{}", time::time_of_day(e.time_gps_s));
        compared += 1;
    }
    assert_eq!(compared, 4);
    assert_eq!(r02_excluded, 3);
}
