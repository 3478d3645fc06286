//! The EMT of chosen user-epochs of a run file under SPEC §9.1's rule and
//! under MAAST for ARAIM 2's: MAAST 2 forms a single-satellite mode's
//! prior as P_sat prod_j (1 - P_j) / (1 - P_sat) (`determine_subsets_v5.m`),
//! just below P_EMT = P_sat = 1e-5, so its EMT (`compute_emt.m`: the
//! largest vertical threshold over the modes with prior >= P_EMT) leaves
//! out every single-satellite mode; ours takes the prior as P_sat and
//! counts them. A diagnostic for docs/AVAILABILITY.md "The adjusted
//! position estimator" (EMT).
//!
//! `cargo run --release -p raim-availability --example emt_rule -- RUN.toml LAT_DEG,LON_DEG,T_S ...`
//!
//! Prints per user-epoch (T_S in GPS seconds of week, on the run's time
//! grid): `lat_deg,lon_deg,t_s,emt_m,emt_without_single_satellite_modes_m,
//! adjusted_t_up` for the output in force (all in view).

use raim_availability::{engine, run};

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let Some((path, points)) = a.get(1).zip(a.get(2..)) else {
        anyhow::bail!("usage: emt_rule RUN.toml LAT_DEG,LON_DEG,T_S ...");
    };
    let study = run::load(std::path::Path::new(path))?;
    let n = study.sats.len();
    let mut m = engine::new_engine();
    let mut obs = Vec::new();
    println!("lat_deg,lon_deg,t_s,emt_m,emt_without_single_satellite_modes_m,adjusted_t_up");
    for p in points {
        let v: Vec<f64> = p.split(',').map(str::parse).collect::<Result<_, _>>()?;
        let [lat, lon, t] = v[..] else {
            anyhow::bail!("{p}: LAT_DEG,LON_DEG,T_S");
        };
        let u = study
            .users
            .iter()
            .find(|u| u.lat_deg == lat && u.lon_deg == lon)
            .ok_or_else(|| anyhow::anyhow!("{p}: no such user"))?;
        let k = study
            .epochs_gps_s
            .iter()
            .position(|&e| (e.rem_euclid(604_800.0) - t).abs() < 1e-6)
            .ok_or_else(|| anyhow::anyhow!("{p}: no such epoch"))?;
        let sky = engine::sky_table(&study, k..k + 1);
        let (x, rot) = engine::user_frame(&study, u);
        engine::visible(&study, &sky[..n], x, &rot, &mut obs);
        engine::evaluate(&study, &mut m, &obs).map_err(|e| anyhow::anyhow!("{e}"))?;
        let out = m.all_in_view();
        let strict = out
            .modes
            .iter()
            .filter(|md| md.status == raim_core::araim::ModeStatus::Monitored)
            .filter(|md| md.events.prior >= study.cfg.p_emt)
            .filter(|md| !(md.events.sats.count_ones() == 1 && md.events.consts == 0))
            .map(|md| md.threshold_m[2])
            .fold(0.0f64, f64::max);
        println!(
            "{lat},{lon},{t},{:.4},{strict:.4},{:.4}",
            out.emt_m, out.adjusted_t[2]
        );
    }
    Ok(())
}
