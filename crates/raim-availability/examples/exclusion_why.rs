//! Why an epoch is unavailable with exclusion: for one user of a run file,
//! each epoch that is available with detection only but not with
//! exclusion, the candidate exclusions that fail and their limits
//! (docs/AVAILABILITY.md "Availability with exclusion").
//!
//! `cargo run --release -p raim-availability --example exclusion_why -- RUN.toml LAT_DEG LON_DEG`

use raim_availability::{engine, run};
use raim_core::araim::ModeStatus;

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let (path, lat, lon) = match a.as_slice() {
        [_, p, la, lo] => (p, la.parse::<f64>()?, lo.parse::<f64>()?),
        _ => anyhow::bail!("usage: exclusion_why RUN.toml LAT_DEG LON_DEG"),
    };
    let study = run::load(std::path::Path::new(path))?;
    let user = run::User {
        name: String::new(),
        lat_deg: lat,
        lon_deg: lon,
        weight: 1.0,
    };
    let (x, rot) = engine::user_frame(&study, &user);
    let mut m = engine::new_engine();
    let mut obs = Vec::new();
    for k in 0..study.epochs_gps_s.len() {
        let sky = engine::sky_table(&study, k..k + 1);
        engine::visible(&study, &sky, x, &rot, &mut obs);
        m.linear(
            &study.cfg,
            &study.ism,
            &study.ism_entries[..],
            &obs,
            raim_core::araim::FdeLimits::UNLIMITED,
        )
        .map_err(|e| anyhow::anyhow!("{e}"))?;
        let aiv = m.all_in_view();
        if !aiv.available() {
            continue;
        }
        let (vpl0, emt0) = (aiv.pl_add.vpl_m, aiv.emt_m);
        let n_gal = obs
            .iter()
            .filter(|o| o.id.system == raim_core::System::Galileo)
            .count();
        let cands: Vec<(usize, u64)> = aiv
            .modes
            .iter()
            .enumerate()
            .filter(|(_, md)| {
                md.status == ModeStatus::Monitored
                    && md.events.sats.count_ones() == 1
                    && md.events.consts == 0
            })
            .map(|(i, md)| (i, md.events.sats))
            .collect();
        for (i, mask) in cands {
            let sat = obs[mask.trailing_zeros() as usize].id;
            match m
                .after_excluding(&study.cfg, &study.ism, i)
                .map_err(|e| anyhow::anyhow!("{e}"))?
            {
                Some(sub) if !sub.available() => println!(
                    "epoch {k}: {} GPS + {n_gal} Galileo in view, all-in-view VPL {vpl0:.1} EMT {emt0:.1}; \
                     without {}{:02}: VPL {:.1} HPL {:.1} EMT {:.1} sigma_acc {:.2} ({:?})",
                    obs.len() - n_gal,
                    sat.system.letter(),
                    sat.prn,
                    sub.pl_add.vpl_m,
                    sub.pl_add.hpl_m,
                    sub.emt_m,
                    sub.sigma_v_acc_m,
                    sub.unavailable
                ),
                Some(_) => {}
                None => println!("epoch {k}: without {}{:02}: not solvable", sat.system.letter(), sat.prn),
            }
        }
    }
    Ok(())
}
