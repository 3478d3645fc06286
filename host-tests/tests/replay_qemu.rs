//! `raim replay --target qemu`: real epochs (0759, the 50 m G24 step from
//! 00:20:00, and the ambiguous stretch) processed by the firmware under
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
