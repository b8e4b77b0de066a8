//! The firmware image: builds the three compensators, the six-axis banks and the chain without an
//! allocator and runs them on a trajectory forever, writing each output to a volatile location
//! as a DAC register would be.
#![no_std]
#![no_main]

use core::panic::PanicInfo;
use core::ptr::{addr_of_mut, write_volatile};

use hystcomp_thumbv7em_example::{
    AXES, BANK_RAM_BYTES, Compensators, RAM_BYTES, chain, desired, hystcomp_chain_step,
    hystcomp_dihc_bank_step, hystcomp_dihc_step, hystcomp_ihc_bank_step, hystcomp_ihc_step,
    hystcomp_wihc_bank_step, hystcomp_wihc_step, six_axes, six_axes_dihc, six_axes_wihc,
};

/// The RAM table, kept in the image so that the host test can read the target's own numbers.
#[used]
#[unsafe(no_mangle)]
pub static HYSTCOMP_RAM_BYTES: [u32; 8] = {
    let mut table = [0u32; 8];
    let mut i = 0;
    while i < 8 {
        table[i] = RAM_BYTES[i] as u32;
        i += 1;
    }
    table
};

/// The six-channel banks' RAM, for the host test.
#[used]
#[unsafe(no_mangle)]
pub static HYSTCOMP_BANK_RAM_BYTES: [u32; 3] = [
    BANK_RAM_BYTES[0] as u32,
    BANK_RAM_BYTES[1] as u32,
    BANK_RAM_BYTES[2] as u32,
];

/// Stands in for four DAC registers (IHC, WIHC, DIHC, the chain).
static mut DAC: [f32; 4] = [0.0; 4];

/// Stands in for the six axes' DAC registers, once per bank (IHC, WIHC, DIHC).
static mut AXES_DAC: [f32; 3 * AXES] = [0.0; 3 * AXES];

/// The entry point (no runtime crate: the linker starts here).
#[unsafe(no_mangle)]
pub extern "C" fn _start() -> ! {
    let Ok(mut c) = Compensators::from_paper() else {
        halt()
    };
    let Ok(mut bank) = six_axes() else { halt() };
    let Ok(mut wihc_bank) = six_axes_wihc() else {
        halt()
    };
    let Ok(mut dihc_bank) = six_axes_dihc() else {
        halt()
    };
    let Ok(mut full) = chain() else { halt() };
    let dac = addr_of_mut!(DAC).cast::<f32>();
    let axes_dac = addr_of_mut!(AXES_DAC).cast::<f32>();
    let mut k: u32 = 0;
    loop {
        let y_d = desired(k, 2000);
        let mut tick = [0.0f32; AXES];
        for (c, d) in tick.iter_mut().enumerate() {
            *d = desired(k.wrapping_add(300 * c as u32), 2000);
        }
        let mut drives = [[0.0f32; AXES]; 3];
        let [ihc_drives, wihc_drives, dihc_drives] = &mut drives;
        if !hystcomp_ihc_bank_step(&mut bank, &tick, ihc_drives)
            || !hystcomp_wihc_bank_step(&mut wihc_bank, &tick, wihc_drives)
            || !hystcomp_dihc_bank_step(&mut dihc_bank, &tick, dihc_drives)
        {
            halt()
        }
        for (c, v) in drives.iter().flatten().enumerate() {
            // SAFETY: `axes_dac` points to the `3 * AXES` floats of `AXES_DAC`, written only
            // here.
            unsafe { write_volatile(axes_dac.add(c), *v) };
        }
        // SAFETY: `dac` points to the four floats of `DAC`, written only here (one thread).
        unsafe {
            write_volatile(dac, hystcomp_ihc_step(&mut c.ihc, y_d));
            write_volatile(dac.add(1), hystcomp_wihc_step(&mut c.wihc, y_d));
            write_volatile(dac.add(2), hystcomp_dihc_step(&mut c.dihc, y_d));
            write_volatile(dac.add(3), hystcomp_chain_step(&mut full, y_d));
        }
        k = k.wrapping_add(1);
    }
}

fn halt() -> ! {
    loop {
        core::hint::spin_loop();
    }
}

#[panic_handler]
fn panic(_: &PanicInfo) -> ! {
    halt()
}
