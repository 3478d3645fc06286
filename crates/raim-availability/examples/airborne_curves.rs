//! The airborne curves of the availability engine side by side, as a
//! Markdown table (docs/AVAILABILITY.md "The Galileo airborne curve"):
//! per elevation, the iono-free airborne sigma (multipath and noise) of
//! the ADD's GPS L1/L5 curves (raim-core's default), of the Galileo
//! E1/E5a table (raim-core's `galileo_e1e5a_sigma_m`), of MAAST for
//! ARAIM 2's ED-259A curve, and that curve with its ionospheric residual;
//! and the whole nominal variance (troposphere included) of the default
//! and of MAAST for ARAIM 2's model.
//!
//! `cargo run --release -p raim-availability --example airborne_curves`

use raim_availability::airborne;
use raim_core::araim::error_model as em;

fn main() {
    println!("| elevation (deg) | GPS L1/L5, ADD (m) | Galileo E1/E5a table (m) | ED-259A as MAAST for ARAIM 2 (m) | the same with its iono residual (m) | ED-259A / table | nominal sigma, ADD GPS curves (m) | nominal sigma, MAAST for ARAIM 2 (m) |");
    println!("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    for k in 1..=18 {
        let el_deg = 5.0 * f64::from(k);
        let el = el_deg.to_radians();
        let gps = (em::iono_free_factor_sq() * em::airborne_variance_m2(el)).sqrt();
        let table = em::galileo_e1e5a_sigma_m(el);
        let ed = airborne::ed259a_maast_airborne_variance_m2(el).sqrt();
        let iono = airborne::ed259a_maast_iono_sigma_m(el);
        let ed_iono = (ed * ed + iono * iono).sqrt();
        let nominal_add = em::nominal_variance_m2(el).sqrt();
        let nominal_maast = airborne::ed259a_maast_variance_m2(el).sqrt();
        println!(
            "| {el_deg:.0} | {gps:.4} | {table:.4} | {ed:.4} | {ed_iono:.4} | {:.2} | {nominal_add:.4} | {nominal_maast:.4} |",
            ed / table
        );
    }
}
