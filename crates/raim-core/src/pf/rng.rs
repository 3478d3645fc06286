//! Seeded, portable randomness for the particle filters: xoshiro256++
//! (`rand_xoshiro`, through `rand_core`) with normal draws by the ziggurat
//! of `rand_distr` (no_std). Draws are taken in `f64` whatever the state
//! precision, so an `f32` and an `f64` run consume the same stream and the
//! host and the Cortex-M4F produce the same sequence for the same seed.

use rand_core::SeedableRng;
use rand_distr::{Distribution, StandardNormal, StandardUniform};

/// The generator every `pf` filter draws from.
pub type PfRng = rand_xoshiro::Xoshiro256PlusPlus;

/// A generator from a 64-bit seed (SplitMix64 expansion, as `rand_core`
/// specifies), identical on every target.
pub fn seeded(seed: u64) -> PfRng {
    PfRng::seed_from_u64(seed)
}

/// One standard normal draw.
#[inline]
pub fn normal(rng: &mut PfRng) -> f64 {
    StandardNormal.sample(rng)
}

/// One uniform draw in [0, 1).
#[inline]
pub fn uniform(rng: &mut PfRng) -> f64 {
    StandardUniform.sample(rng)
}

/// A uniform index in 0..n (n > 0), by multiply-shift on a 32-bit draw;
/// 0 when n is 0.
#[inline]
pub fn index(rng: &mut PfRng, n: usize) -> usize {
    let u = uniform(rng);
    let i = (u * n as f64) as usize;
    if i >= n {
        n.saturating_sub(1)
    } else {
        i
    }
}

/// The generator in `slot`, seeded with 0 if it has none yet (an engine
/// made as [`super::PfRaim::EMPTY`] behaves as one made by `new(0)`).
pub fn or_seed_zero(slot: &mut Option<PfRng>) -> &mut PfRng {
    slot.get_or_insert_with(seeded_zero)
}

/// `seeded(0)`, out of line: it runs once per engine, and the check at
/// each use stays a compare and a branch.
#[cold]
#[inline(never)]
fn seeded_zero() -> PfRng {
    seeded(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Same seed, same stream; the moments of the normal draws match
    /// N(0, 1) within 5 standard errors.
    #[test]
    fn seeded_stream_is_reproducible_and_normal() {
        let mut a = seeded(7);
        let mut b = seeded(7);
        for _ in 0..100 {
            assert_eq!(normal(&mut a).to_bits(), normal(&mut b).to_bits());
        }
        let n = 20_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let x = normal(&mut a);
            s1 += x;
            s2 += x * x;
        }
        let mean = s1 / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!(mean.abs() < 5.0 / (n as f64).sqrt());
        assert!((var - 1.0).abs() < 5.0 * (2.0 / n as f64).sqrt());
        for _ in 0..1000 {
            assert!(index(&mut a, 7) < 7);
        }
        assert_eq!(index(&mut a, 0), 0);
    }
}
