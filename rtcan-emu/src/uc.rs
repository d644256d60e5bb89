//! The few functions of Debian's libunicorn (Unicorn 2, C API of `unicorn/unicorn.h`)
//! this crate needs, declared by hand so that the build does not compile Unicorn from
//! source. Constants are the header's values (checked against libunicorn-dev 2.0.1).
#![allow(non_camel_case_types)]
use core::ffi::c_void;

pub type uc_engine = c_void;
pub type uc_hook = usize;
pub type uc_err = i32;

pub const UC_ARCH_ARM: i32 = 1;
pub const UC_MODE_THUMB: i32 = 16;
pub const UC_MODE_MCLASS: i32 = 32;
/// `UC_CTL_WRITE(UC_CTL_CPU_MODEL, 1)`.
pub const UC_CTL_CPU_MODEL_WRITE: u32 = 0x4400_0007;
pub const UC_CPU_ARM_CORTEX_M3: i32 = 8;

pub const UC_PROT_ALL: u32 = 7;
pub const UC_HOOK_INTR: i32 = 1;
pub const UC_HOOK_BLOCK: i32 = 8;
pub const UC_HOOK_MEM_UNMAPPED: i32 = 112;
pub const UC_HOOK_MEM_WRITE: i32 = 2048;

pub const REG_R0: i32 = 66;
pub const REG_SP: i32 = 12;
pub const REG_LR: i32 = 10;
pub const REG_PC: i32 = 11;
pub const REG_R12: i32 = 78;
pub const REG_XPSR: i32 = 120;
pub const REG_PRIMASK: i32 = 123;
pub const REG_BASEPRI: i32 = 124;
pub const REG_FAULTMASK: i32 = 126;

pub type MmioRead = extern "C" fn(*mut uc_engine, u64, u32, *mut c_void) -> u64;
pub type MmioWrite = extern "C" fn(*mut uc_engine, u64, u32, u64, *mut c_void);

#[link(name = "unicorn")]
extern "C" {
    pub fn uc_open(arch: i32, mode: i32, uc: *mut *mut uc_engine) -> uc_err;
    pub fn uc_close(uc: *mut uc_engine) -> uc_err;
    pub fn uc_ctl(uc: *mut uc_engine, control: u32, ...) -> uc_err;
    pub fn uc_mem_map(uc: *mut uc_engine, address: u64, size: usize, perms: u32) -> uc_err;
    pub fn uc_mem_map_ptr(
        uc: *mut uc_engine,
        address: u64,
        size: usize,
        perms: u32,
        ptr: *mut c_void,
    ) -> uc_err;
    pub fn uc_mmio_map(
        uc: *mut uc_engine,
        address: u64,
        size: usize,
        read_cb: MmioRead,
        user_data_read: *mut c_void,
        write_cb: MmioWrite,
        user_data_write: *mut c_void,
    ) -> uc_err;
    pub fn uc_mem_write(
        uc: *mut uc_engine,
        address: u64,
        bytes: *const c_void,
        size: usize,
    ) -> uc_err;
    pub fn uc_mem_read(uc: *mut uc_engine, address: u64, bytes: *mut c_void, size: usize)
        -> uc_err;
    pub fn uc_reg_write(uc: *mut uc_engine, regid: i32, value: *const c_void) -> uc_err;
    pub fn uc_reg_read(uc: *mut uc_engine, regid: i32, value: *mut c_void) -> uc_err;
    pub fn uc_emu_start(
        uc: *mut uc_engine,
        begin: u64,
        until: u64,
        timeout: u64,
        count: usize,
    ) -> uc_err;
    pub fn uc_emu_stop(uc: *mut uc_engine) -> uc_err;
    pub fn uc_hook_add(
        uc: *mut uc_engine,
        hh: *mut uc_hook,
        hook_type: i32,
        callback: *mut c_void,
        user_data: *mut c_void,
        begin: u64,
        end: u64,
        ...
    ) -> uc_err;
}
