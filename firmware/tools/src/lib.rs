//! What `firmware/build` needs on the host, without a toolchain of its
//! own: a 32-bit ELF's loadable segments and sections ([`elf`]), and UF2
//! images made from them ([`uf2`]). The `ppmc-fwtool` binary runs them;
//! `ppmc-emu` loads the same segments into its emulated flash.

pub mod elf;
pub mod uf2;
