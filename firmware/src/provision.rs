//! The provisioned unit configuration: its own output section,
//! `.raim_config` (`raim_proto::unit::PROVISION_BYTES`, after `.raim_key`
//! in `memory.x` / `memory-stm32f4.x`). The image ships it erased (0xFF):
//! such a unit boots Unconfigured. Installation writes the sealed
//! configuration into the image it programs (`raim provision`, or
//! `raim_qemu::provision_config` for an ELF); the seal is an HMAC under the
//! unit's key when it has one, SHA-256 otherwise, so a corrupt or forged
//! section is refused at boot and the unit stays Unconfigured.

use raim_proto::auth::BootEntropy;
use raim_proto::unit::PROVISION_BYTES;

/// The section; erased flash is all ones.
#[link_section = ".raim_config"]
#[used]
static CONFIG: [u8; PROVISION_BYTES] = [0xFF; PROVISION_BYTES];

/// The section as programmed. `black_box`: the build's erased value must
/// not be folded in, since installation changes the bytes after linking.
pub fn section() -> &'static [u8; PROVISION_BYTES] {
    core::hint::black_box(&CONFIG)
}

/// SRAM left as it powered up (NOLOAD, never written): on silicon its
/// power-on state differs from part to part and boot to boot, and it feeds
/// the boot nonce. QEMU powers up with zeros (docs/SAFETY.md "Boot nonce").
#[link_section = ".uninit.raim_noise"]
static mut NOISE: core::mem::MaybeUninit<[u8; 32]> = core::mem::MaybeUninit::uninit();

/// The entropy of this boot: the power-on SRAM noise, the SysTick count
/// after the set-up so far and, when the board has one that worked, its
/// hardware random source's 32 bytes (`Parts::hardware_entropy`), all
/// XORed together: the result is at least as unpredictable as the most
/// unpredictable of them. The unit's identity is XORed in too, the part's
/// unique ID (`unique`, three words, where the board has one) into bytes
/// 0-11 and the
/// provisioned unit ID (`unit_id::provisioned`) into bytes 16-31, so that
/// two units with the same key, reset count and entropy still boot with
/// different nonces (issue 35, a fleet key). The
/// boot nonce is SHA-256 of it with the key and the reset count
/// (`raim_proto::auth::boot_nonce`). Without hardware entropy, under QEMU,
/// it changes with the reset count and the unit only.
pub fn entropy(ticks: u32, hardware: Option<&[u8; 32]>, unique: Option<[u32; 3]>) -> BootEntropy {
    // SAFETY: a plain read of 32 bytes of RAM owned by this module; any bit
    // pattern is a value. Never written, so it keeps its power-on state.
    let mut e = unsafe { core::ptr::read_volatile(core::ptr::addr_of!(NOISE).cast::<[u8; 32]>()) };
    let [u0, u1, u2] = unique.unwrap_or([0; 3]);
    let [p0, p1, p2, p3] = crate::unit_id::provisioned();
    let words = [ticks ^ u0, u1, u2, 0, p0, p1, p2, p3];
    for (b, w) in e.iter_mut().zip(words.iter().flat_map(|w| w.to_le_bytes())) {
        *b ^= w;
    }
    if let Some(h) = hardware {
        for (b, r) in e.iter_mut().zip(h) {
            *b ^= r;
        }
    }
    BootEntropy {
        bytes: e,
        hardware: hardware.is_some(),
    }
}
