//! The unit's key for authenticated configuration (`AuthConfigure`,
//! raim-proto `auth`, HMAC-SHA256), provisioned per unit into flash
//! (docs/SAFETY.md "Key provisioning").
//!
//! The key has its own output section, `.raim_key` (32 bytes, placed after
//! `.rodata` by `memory.x` / `memory-stm32f4.x`). The firmware image ships
//! it erased (all 0xFF): such a unit has no key and takes plain
//! `Configure` (answering `AuthNotProvisioned` to `AuthConfigure`).
//! Production writes each unit's own key into that section of the image it
//! programs (`raim_qemu::provision_key` does it to an ELF); from then on
//! only authenticated configurations are accepted. The key never travels
//! over the link, one image serves every unit, and one unit's key opens no
//! other unit. On the STM32F4, read-out protection (RDP level 1 or 2) keeps
//! it from a debugger.

/// The key's section; erased flash is all ones.
#[link_section = ".raim_key"]
#[used]
static KEY: [u8; 32] = [0xFF; 32];

/// The provisioned key, or `None` when the section is erased.
pub fn provisioned() -> Option<raim_proto::AuthKey> {
    // SAFETY: a plain read of a static array; volatile, so that the build's
    // erased value is not folded in: production changes the bytes after
    // linking.
    let key = unsafe { core::ptr::read_volatile(core::ptr::addr_of!(KEY)) };
    (!key.iter().all(|&b| b == 0xFF)).then_some(key)
}
