//! Linear algebra on fixed buffers shared by every method: Householder QR
//! (`qr`) and the parity space built on it (`parity`, SPEC §2).

pub mod parity;
pub mod qr;
