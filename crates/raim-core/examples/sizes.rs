//! Prints the stack footprint of the core's per-epoch objects at N = 32.
//! Run: cargo run -p raim-core --example sizes --release
use raim_core::linalg::parity::Parity;
use raim_core::snapshot::fde::FdeOutcome;
use raim_core::solve::Solution;
use raim_core::{EpochResult, Raim};

fn main() {
    println!(
        "Parity<32>      {:>6} B",
        core::mem::size_of::<Parity<32>>()
    );
    println!(
        "Solution<32>    {:>6} B",
        core::mem::size_of::<Solution<32>>()
    );
    println!(
        "FdeOutcome<32>  {:>6} B",
        core::mem::size_of::<FdeOutcome<32>>()
    );
    println!(
        "EpochResult<32> {:>6} B",
        core::mem::size_of::<EpochResult<32>>()
    );
    println!("Raim<32>        {:>6} B", core::mem::size_of::<Raim<32>>());
}
