//! The firmware image: builds the three compensators without an allocator and runs them on a
//! trajectory forever, writing each output to a volatile location as a DAC register would be.
#![no_std]
#![no_main]

use core::panic::PanicInfo;
use core::ptr::{addr_of_mut, write_volatile};

use hystcomp_thumbv7em_example::{
    Compensators, RAM_BYTES, desired, hystcomp_dihc_step, hystcomp_ihc_step, hystcomp_wihc_step,
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

/// Stands in for three DAC registers.
static mut DAC: [f32; 3] = [0.0; 3];

/// The entry point (no runtime crate: the linker starts here).
#[unsafe(no_mangle)]
pub extern "C" fn _start() -> ! {
    let Ok(mut c) = Compensators::from_paper() else {
        halt()
    };
    let dac = addr_of_mut!(DAC).cast::<f32>();
    let mut k: u32 = 0;
    loop {
        let y_d = desired(k, 2000);
        // SAFETY: `dac` points to the three floats of `DAC`, written only here (one thread).
        unsafe {
            write_volatile(dac, hystcomp_ihc_step(&mut c.ihc, y_d));
            write_volatile(dac.add(1), hystcomp_wihc_step(&mut c.wihc, y_d));
            write_volatile(dac.add(2), hystcomp_dihc_step(&mut c.dihc, y_d));
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
