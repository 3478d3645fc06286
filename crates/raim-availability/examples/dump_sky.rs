//! Every user-epoch of a run file as the ARAIM engine saw it, for a
//! comparison with another ARAIM implementation on the same inputs
//! (docs/AVAILABILITY.md "Against the ADD v4.2 reference implementation",
//! `scripts/availability_maast_compare.sh`).
//!
//! `cargo run --release -p raim-availability --example dump_sky -- RUN.toml OUT_DIR`
//!
//! Writes `OUT_DIR/sky.csv`, one row per satellite in view:
//! `case,sys,prn,g_e,g_n,g_u,el_deg,c_int_m2,c_acc_m2,b_nom_m,p_sat,p_const`
//! (sys 1 = GPS, 2 = Galileo; the G row's ENU part with the ADD's sign;
//! C_int and C_acc as raim-core formed them), and `OUT_DIR/ours.csv`, one
//! row per user-epoch: `case,lat_deg,lon_deg,epoch,n_sats,modes,vpl_m,
//! hpl_m,emt_m,sigma_v_acc_m,available,vpl_root_m,hpl_root_m` (the
//! engine's detection-only outputs, +inf when refused; the PLs the
//! availability judges are the ADD's bisection output, the `_root` ones
//! the exact roots of the PL equations). Numbers are written with 17 significant
//! digits, so the other side reads the same doubles.
//!
//! `dump_sky RUN.toml OUT_DIR --by-latitude` writes the satellite rows
//! into one file per grid latitude instead, `OUT_DIR/sky_lat<LAT>.csv`
//! (`LAT` the user's latitude in whole degrees, e.g. `sky_lat-90.csv`),
//! with the same header and the same case numbers as `ours.csv`: a world
//! grid's sky is about a gigabyte in one file, so the reference reads
//! and runs it band by band (`scripts/availability_maast_world.sh`).
//!
//! `dump_sky RUN.toml OUT_DIR --no-sky` writes `ours.csv` alone, for a
//! comparison with a tool that forms its own sky from the almanacs
//! (MAAST for ARAIM 2, `scripts/maast2/compare.py`).

use std::fmt::Write as _;

use raim_availability::{engine, run};

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let (path, out, by_latitude, no_sky) = match a.as_slice() {
        [_, p, o] => (p, std::path::PathBuf::from(o), false, false),
        [_, p, o, f] if f == "--by-latitude" => (p, std::path::PathBuf::from(o), true, false),
        [_, p, o, f] if f == "--no-sky" => (p, std::path::PathBuf::from(o), false, true),
        _ => anyhow::bail!("usage: dump_sky RUN.toml OUT_DIR [--by-latitude | --no-sky]"),
    };
    let mut study = run::load(std::path::Path::new(path))?;
    study.exclusion = run::ExclusionSpec::None;
    std::fs::create_dir_all(&out)?;
    const SKY_HEAD: &str =
        "case,sys,prn,g_e,g_n,g_u,el_deg,c_int_m2,c_acc_m2,b_nom_m,p_sat,p_const\n";
    // One sky file, or one per latitude (name -> open writer).
    let mut skies: std::collections::BTreeMap<String, std::io::BufWriter<std::fs::File>> =
        std::collections::BTreeMap::new();
    let mut sky_csv = String::new();
    let mut ours = String::from(
        "case,lat_deg,lon_deg,epoch,n_sats,modes,vpl_m,hpl_m,emt_m,sigma_v_acc_m,available,vpl_root_m,hpl_root_m\n",
    );
    let sky = engine::sky_table(&study, 0..study.epochs_gps_s.len());
    let n = study.sats.len();
    let mut m = engine::new_engine();
    let mut obs = Vec::new();
    let mut case = 0usize;
    for u in &study.users {
        let (x, rot) = engine::user_frame(&study, u);
        let sky_name = if by_latitude {
            format!("sky_lat{:.0}.csv", u.lat_deg)
        } else {
            String::from("sky.csv")
        };
        if !no_sky && !skies.contains_key(&sky_name) {
            let mut w = std::io::BufWriter::new(std::fs::File::create(out.join(&sky_name))?);
            std::io::Write::write_all(&mut w, SKY_HEAD.as_bytes())?;
            skies.insert(sky_name.clone(), w);
        }
        for (k, row) in sky.chunks_exact(n).enumerate() {
            case += 1;
            engine::visible(&study, row, x, &rot, &mut obs);
            let o = engine::evaluate(&study, &mut m, &obs).map_err(|e| anyhow::anyhow!("{e}"))?;
            let sats = if o.refused || no_sky {
                &[][..]
            } else {
                m.satellites()
            };
            for s in sats {
                let sys = match s.id.system {
                    raim_core::System::Gps => 1,
                    _ => 2,
                };
                let p_const = study.ism.p_const[s.id.system.index()].unwrap_or(f64::NAN);
                let el_deg = (-s.g_enu[2]).asin().to_degrees();
                writeln!(
                    sky_csv,
                    "{case},{sys},{},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e}",
                    s.id.prn, s.g_enu[0], s.g_enu[1], s.g_enu[2], el_deg, s.c_int_m2, s.c_acc_m2,
                    s.b_nom_m, s.p_sat, p_const
                )?;
            }
            if let Some(w) = skies.get_mut(&sky_name) {
                std::io::Write::write_all(w, sky_csv.as_bytes())?;
            }
            sky_csv.clear();
            let root = if o.refused {
                [f64::INFINITY; 2]
            } else {
                let p = m.all_in_view().pl_exact;
                [p.vpl_m, p.hpl_m]
            };
            writeln!(
                ours,
                "{case},{},{},{k},{},{},{:.17e},{:.17e},{:.17e},{:.17e},{},{:.17e},{:.17e}",
                u.lat_deg,
                u.lon_deg,
                obs.len(),
                o.modes,
                o.vpl_m,
                o.hpl_m,
                o.emt_m,
                o.sigma_v_acc_m,
                u8::from(o.available),
                root[0],
                root[1]
            )?;
        }
    }
    for w in skies.values_mut() {
        std::io::Write::flush(w)?;
    }
    std::fs::write(out.join("ours.csv"), ours)?;
    eprintln!("{case} user-epochs written to {}", out.display());
    Ok(())
}
