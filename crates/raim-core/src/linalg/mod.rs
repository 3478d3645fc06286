//! Linear algebra on fixed buffers shared by every method: Householder QR
//! (`qr`) and the parity space built on it (`parity`, SPEC §2).

pub mod parity;
pub mod qr;

/// The kernels the linear algebra runs for a scalar type: algorithm
/// choices, keyed on the type, that give the same quantities up to their
/// last bits. Each engine keeps its own choice bit for bit; the f64 engine
/// (the host) takes the faster forms, the f32 engine (the M4F, which has no
/// vector unit and no flash to spare) the plain ones (docs/CORE.md,
/// "Householder column norms" and "Reductions in lanes").
pub trait Kernels {
    /// Whether the Householder QR forms its column norms by one unscaled
    /// pass (`qr::make_reflector`) rather than the scaled two-pass form.
    /// The f32 engine keeps the scaled form: its flash margin has no room
    /// for a second reflector, and its f32 tests' tolerances sit within
    /// 1-2x of the rounding that a last-bit change moves at random.
    const ONE_PASS_QR: bool;
    /// Whether the QR's hot reductions (the reflections' dot products and
    /// the column sums of squares, `qr::dot_lanes`) are summed in four
    /// interleaved partial sums, which the compiler vectorises, rather than
    /// left to right. The same engines also factor m = 4 and 5 columns with
    /// the count fixed at compile time and build the linearised model in
    /// passes (`solve::solve_linear`), both bit for bit with the plain
    /// forms; on the M4F each copy would cost flash.
    const LANE_SUMS: bool;
}

impl Kernels for f64 {
    const ONE_PASS_QR: bool = true;
    const LANE_SUMS: bool = true;
}

impl Kernels for f32 {
    const ONE_PASS_QR: bool = false;
    const LANE_SUMS: bool = false;
}
