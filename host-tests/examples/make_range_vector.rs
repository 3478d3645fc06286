//! Writes `vectors/ranges_example.jsonl`: pseudorange-form epochs
//! (docs/FORMATS.md) seen from the 0759 station on 2024-02-29 from 12:00:00
//! UTC, 1 s apart: clean, one 60 m fault on G05, faults on G03 and G08,
//! GPS + Galileo with a 45 m fault on E06, five satellites, four satellites
//! (too few). Made by `qemu_common::range_vectors(7)`, the generator of the
//! QEMU tests; `raim qemu --input` on it shows positions in the NMEA.
//! `cargo run --release -p host-tests --example make_range_vector`

#[path = "../tests/qemu_common/mod.rs"]
mod qemu_common;

use std::io::Write;

fn main() -> std::io::Result<()> {
    let path = host_tests::vector_path("ranges_example.jsonl");
    let mut f = std::fs::File::create(&path)?;
    writeln!(
        f,
        "# made by host-tests/examples/make_range_vector.rs (see there)"
    )?;
    for (t, sats, apriori) in qemu_common::range_vectors(7) {
        let sats: Vec<serde_json::Value> = sats
            .iter()
            .map(|s| {
                let mut v = serde_json::json!({
                    "sys": s.id.system.letter().to_string(), "prn": s.id.prn,
                    "pseudorange_m": s.pseudorange_m, "position_m": s.position_m,
                });
                if let Some(sigma) = s.sigma_m {
                    v["sigma_m"] = sigma.into();
                }
                v
            })
            .collect();
        let mut e = serde_json::json!({ "time_s": t, "sats": sats });
        if let Some(a) = apriori {
            e["apriori_m"] = serde_json::json!(a);
        }
        writeln!(f, "{e}")?;
    }
    println!("wrote {}", path.display());
    Ok(())
}
