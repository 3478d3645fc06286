//! The stream receiver's week-rollover pivot from the build date
//! (`stream::PIVOT_WEEK`): the GPS week of `SOURCE_DATE_EPOCH` when set
//! (reproducible builds), else of the build machine's clock, written as
//! the constant `BUILD_GPS_WEEK` into `$OUT_DIR/build_week.rs`. The script reruns only when that variable
//! changes, so a target directory keeps the week of its first build.

use std::time::{SystemTime, UNIX_EPOCH};

/// Unix time of the GPS epoch, 1980-01-06T00:00:00Z, s.
const GPS_EPOCH_UNIX_S: i64 = 315_964_800;
const WEEK_S: i64 = 604_800;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=SOURCE_DATE_EPOCH");
    let unix_s = match std::env::var("SOURCE_DATE_EPOCH") {
        Ok(v) => match v.trim().parse::<i64>() {
            Ok(s) => s,
            Err(e) => {
                println!("cargo:warning=SOURCE_DATE_EPOCH={v:?} is not a Unix time ({e})");
                std::process::exit(1);
            }
        },
        Err(_) => match SystemTime::now().duration_since(UNIX_EPOCH) {
            Ok(d) => i64::try_from(d.as_secs()).unwrap_or(i64::MAX),
            Err(e) => {
                println!("cargo:warning=the build machine's clock is before 1970 ({e})");
                std::process::exit(1);
            }
        },
    };
    let week = (unix_s - GPS_EPOCH_UNIX_S).div_euclid(WEEK_S);
    if week < 0 {
        println!("cargo:warning=build date {unix_s} s is before the GPS epoch");
        std::process::exit(1);
    }
    let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    let code = format!(
        "/// The GPS week of this build's date (build.rs).\npub const BUILD_GPS_WEEK: i64 = {week};\n"
    );
    if let Err(e) = std::fs::write(out.join("build_week.rs"), code) {
        println!("cargo:warning=cannot write build_week.rs: {e}");
        std::process::exit(1);
    }
}
