//! `raim rtcm-fault`: a receiver's RTCM 3 stream re-encoded with seeded
//! faults (`raim_recv::msm_fault`): a step, ramp, clock jump or noise of
//! the `raim replay --fault` vocabulary (`raim_gnss::faults`, the same
//! parser and scenario files), and ARAIM constellation faults of
//! `--araim-const-fault` (the replay's parser), written into the MSM
//! pseudoranges of the satellites they touch, every signal alike, with each frame's CRC-24Q
//! recomputed and every other bit kept. The result can be sent to a unit's
//! link UART, or replayed with `raim replay --rtcm3`, as a receiver's
//! output with a faulty satellite or constellation (docs/RECEIVERS.md
//! "Faults in a stream").

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use raim_gnss::faults::{FaultPlan, Scenario};

#[derive(Debug, Clone, Args)]
pub struct RtcmFaultArgs {
    /// The RTCM 3 stream to read (a file).
    #[arg(long = "in", value_name = "FILE")]
    pub input: PathBuf,
    /// Where to write the faulted stream.
    #[arg(long = "out", value_name = "FILE")]
    pub output: PathBuf,
    /// A fault, as `raim replay --fault`: step:E11:30@+600, ramp:G06:0.5@01:00:00, step:E:50@+300..+900, clock:300@+60, noise:all:t3:1.0; times from the stream's first MSM (+S) or GPS times of day of its day; repeatable.
    #[arg(long = "fault", value_name = "SPEC", allow_hyphen_values = true)]
    pub faults: Vec<String>,
    /// A TOML scenario file, as `raim replay --scenario` (docs/REPLAY.md "Scenario files").
    #[arg(long, value_name = "FILE")]
    pub scenario: Option<PathBuf>,
    /// Seed of the injected noise (overrides the scenario's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// A constellation-wide fault, as `raim replay --araim-const-fault`: SYS:COMMON_M:E_M,N_M,U_M@START[..END], a common range error plus the range change of a shift (east, north, up) of that constellation's solution at the stream's station (RTCM 1005/1006); repeatable.
    #[arg(
        long = "araim-const-fault",
        value_name = "SPEC",
        allow_hyphen_values = true
    )]
    pub araim_const_faults: Vec<String>,
}

/// The plan of `args`, its times counted from `first_gps_s`.
fn plan(args: &RtcmFaultArgs, first_gps_s: f64) -> Result<FaultPlan> {
    let mut plan = match &args.scenario {
        Some(p) => Scenario::load(p)?.plan(first_gps_s)?,
        None => FaultPlan::default(),
    };
    for f in &args.faults {
        plan.faults
            .push(FaultPlan::parse_cli(f, first_gps_s).with_context(|| format!("--fault {f}"))?);
    }
    if let Some(s) = args.seed {
        plan.seed = s;
    }
    Ok(plan)
}

pub fn run(args: &RtcmFaultArgs) -> Result<()> {
    if args.faults.is_empty() && args.scenario.is_none() && args.araim_const_faults.is_empty() {
        bail!("rtcm-fault: no fault given (--fault SPEC, --scenario FILE or --araim-const-fault SPEC)");
    }
    let bytes =
        std::fs::read(&args.input).with_context(|| format!("--in {}", args.input.display()))?;
    let first = raim_recv::msm_fault::first_msm_gps_s(&bytes).with_context(|| {
        format!(
            "--in {}: {}",
            args.input.display(),
            raim_recv::msm_fault::MsmFaultError::NoMsm
        )
    })?;
    let plan = plan(args, first)?;
    let shifts = args
        .araim_const_faults
        .iter()
        .map(|s| {
            let f = crate::replay::araim::ConstFault::parse(s, first)?;
            Ok(raim_recv::msm_fault::ConstellationShift {
                system: f.system,
                common_m: f.common_m,
                shift_enu_m: f.shift_enu_m,
                start_s: f.start_gps_s,
                end_s: f.end_gps_s,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let table = raim_recv::msm_fault::constellation_table(&bytes, &shifts)
        .with_context(|| format!("--in {}", args.input.display()))?;
    let out = raim_recv::msm_fault::fault_stream_with(&bytes, &plan, &table)
        .with_context(|| format!("--in {}", args.input.display()))?;
    if out.cells_faulted == 0 {
        bail!(
            "--in {}: the faults move no pseudorange of the stream (no MSM of the satellites they name within their times; {} MSM frames unread); nothing written",
            args.input.display(),
            out.msm_unread
        );
    }
    std::fs::write(&args.output, &out.bytes)
        .with_context(|| format!("--out {}", args.output.display()))?;
    writeln!(
        std::io::stdout(),
        "{}: {} bytes, {} frames; {} MSM rewritten ({} unread), {} pseudoranges moved, {} rough ranges moved, {} phase ranges dropped; first MSM at GPS {} (time of week {:.3} s)",
        args.output.display(),
        out.bytes.len(),
        out.frames,
        out.msm_faulted,
        out.msm_unread,
        out.cells_faulted,
        out.rough_moved,
        out.phase_dropped,
        raim_gnss::time::time_of_day(first),
        first
    )?;
    Ok(())
}
