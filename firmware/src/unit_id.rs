//! The unit's identity in its boot nonce (issue 35, "A fleet key"): two
//! units that share a key must not boot with the same nonce, or a frame
//! made for one would verify on the other. The identity is the part's
//! own unique ID where the board has one (the STM32F4's 96-bit UID,
//! `Board::unique_id`) and a provisioned unit ID: 16 bytes in their own
//! flash output section, `.raim_unit` (after `.raim_config` in
//! `memory.x` / `memory-stm32f4.x`), erased (0xFF) in the image and
//! written per unit by production as the key is
//! (`raim_qemu::write_section`). On a board without a unique ID
//! (mps2-an386, and QEMU's netduinoplus2, which does not model it) the
//! provisioned ID is the only identity: units sharing a key must then
//! each be given their own (docs/SAFETY.md "Boot nonce").

/// The section; erased flash is all ones. Words, so that it is read in
/// four loads.
#[link_section = ".raim_unit"]
#[used]
static UNIT_ID: [u32; 4] = [u32::MAX; 4];

/// The provisioned unit ID, as four words (all ones when none was
/// written), for the boot entropy (`provision::entropy`).
pub fn provisioned() -> [u32; 4] {
    // SAFETY: a plain read of a static array; volatile, so that the
    // build's erased value is not folded in: production changes the bytes
    // after linking.
    unsafe { core::ptr::read_volatile(core::ptr::addr_of!(UNIT_ID)) }
}
