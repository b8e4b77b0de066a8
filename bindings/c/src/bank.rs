//! Banks of compensators: many channels (the axes of a stage, the actuators of a deformable
//! mirror), one handle, contiguous arrays in and out (issue 16).

use std::ffi::{c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};

use hystcomp_io::bank::{Channel, MAX_CHANNELS, ModelSet, ModelSetError, ScaledBank};

use crate::HystcompStatus;
use crate::args::{check_array, clear_out, doubles, handle, path_arg, put_handle};
use crate::boundary::{Failure, boundary, model_file_status};
use crate::compensator::{method_arg, unstable_delay};
use crate::model::{HystcompModel, model_arg};

/// The most channels a bank holds: 65 536 (`hystcomp_io::bank::MAX_CHANNELS`), checked before
/// any array is read.
pub const HYSTCOMP_MAX_CHANNELS: usize = 65536;
const _: () = assert!(HYSTCOMP_MAX_CHANNELS == MAX_CHANNELS);

/// A bank of compensators of one method, one channel per model, stepped together once per
/// control tick (opaque).
///
/// Created by `hystcomp_bank_from_model_set` or `hystcomp_bank_from_models`, released by
/// `hystcomp_bank_free`. Channel `c` gives what a `HystcompCompensator` made from its own
/// model gives, bit for bit.
pub struct HystcompBank {
    pub(crate) inner: ScaledBank,
}

impl From<ModelSetError> for Failure {
    fn from(e: ModelSetError) -> Self {
        let status = match &e {
            ModelSetError::Set { .. } => HystcompStatus::InvalidModelFile,
            ModelSetError::File { error, .. } => model_file_status(error),
            ModelSetError::Channel { error, .. } => Failure::from(error.clone()).status,
            ModelSetError::Write(_) => HystcompStatus::Io,
            ModelSetError::Bank(core) => crate::boundary::core_status(core),
        };
        Failure::new(status, e.to_string())
    }
}

/// The drive limits of `limits_len` pairs `(min, max)` at `limits` (NULL and 0: none).
///
/// # Safety
/// When `limits` is not NULL it must point to `2 * limits_len` readable doubles.
unsafe fn limits_arg(
    limits: *const f64,
    limits_len: usize,
    channels: usize,
) -> Result<Option<Vec<(f64, f64)>>, Failure> {
    if limits_len == 0 {
        return Ok(None);
    }
    if limits_len != 1 && limits_len != channels {
        return Err(Failure::invalid(format!(
            "limits_len {limits_len}: give 0 (each channel's identified range), 1 (one pair for \
             every channel) or one pair per channel ({channels})"
        )));
    }
    // SAFETY: `2 * limits_len` doubles (the caller's contract); `limits_len <= channels <=
    // HYSTCOMP_MAX_CHANNELS`, so the product cannot overflow.
    let values = unsafe { doubles(limits, 2 * limits_len, "limits") }?;
    Ok(Some(values.chunks_exact(2).map(|p| (p[0], p[1])).collect()))
}

/// Creates a bank from a model set, in each channel's physical units: desired positions in
/// (e.g. um), drive voltages out (e.g. V), one per channel.
///
/// - `path`: a model-set file (`{"format": "hystcomp-model-set", ...}`, e.g.
///   `models/table1-xyz-set.json`), a directory of model files (one channel per `*.json`, in
///   the order of their names) or a single model file (one channel).
/// - `method`: as `hystcomp_compensator_from_model_file` (`"ihc"`, `"wihc-guarded"`, ...), the
///   same for every channel.
/// - `limits`, `limits_len`: `limits_len` pairs `(v_min, v_max)` in each channel's voltage
///   unit, `limits[2 c]` and `limits[2 c + 1]`: 0 pairs (`limits` may be NULL: each channel's
///   identified range), 1 pair (every channel) or one pair per channel.
/// - `flags`: 0 or `HYSTCOMP_ALLOW_UNSTABLE_DELAY`.
/// - `out`: receives the handle (NULL on failure). Free it with `hystcomp_bank_free`.
///
/// A channel refused (wrong direction, not invertible over its limits, an unstable delayed
/// loop, creep or vibration links) fails with that channel's status; the message begins with
/// `channel K (NAME): `.
///
/// # Safety
/// `path` and `method` must be NUL-terminated strings or NULL; `limits` must point to
/// `2 * limits_len` doubles or be NULL; `out` must be valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_bank_from_model_set(
    path: *const c_char,
    method: *const c_char,
    limits: *const f64,
    limits_len: usize,
    flags: c_int,
    out: *mut *mut HystcompBank,
) -> c_int {
    boundary(|| {
        // SAFETY: `out` is valid or NULL (the caller's contract).
        unsafe { clear_out(out) }?;
        let unstable = unstable_delay(flags)?;
        // SAFETY: NUL-terminated or NULL (the caller's contract).
        let path = unsafe { path_arg(path, "path") }?;
        // SAFETY: as above.
        let method = unsafe { method_arg(method) }?;
        let set = ModelSet::load(&path)?;
        // SAFETY: `2 * limits_len` doubles or NULL (the caller's contract).
        let limits = unsafe { limits_arg(limits, limits_len, set.len()) }?;
        let inner = ScaledBank::new(&set, method, limits.as_deref(), unstable)?;
        // SAFETY: `out` was checked non-NULL by `clear_out`.
        unsafe { put_handle(out, HystcompBank { inner }) };
        Ok(())
    })
}

/// Creates a bank from models in memory: `models[c]` is channel `c`'s model
/// (`hystcomp_model_load`, `hystcomp_model_from_values`, `hystcomp_identify`), `channels` of
/// them (1 to `HYSTCOMP_MAX_CHANNELS`); the models are copied and may be freed after. The
/// other arguments are those of `hystcomp_bank_from_model_set`; the channels are named
/// `channel_0`, `channel_1`, ... in messages.
///
/// # Safety
/// `models` must point to `channels` live model handles (or be NULL); `method` a
/// NUL-terminated string or NULL; `limits` `2 * limits_len` doubles or NULL; `out` valid for
/// one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_bank_from_models(
    models: *const *const HystcompModel,
    channels: usize,
    method: *const c_char,
    limits: *const f64,
    limits_len: usize,
    flags: c_int,
    out: *mut *mut HystcompBank,
) -> c_int {
    boundary(|| {
        // SAFETY: `out` is valid or NULL (the caller's contract).
        unsafe { clear_out(out) }?;
        let unstable = unstable_delay(flags)?;
        // SAFETY: NUL-terminated or NULL (the caller's contract).
        let method = unsafe { method_arg(method) }?;
        if models.is_null() {
            return Err(Failure::null("models"));
        }
        if channels == 0 || channels > HYSTCOMP_MAX_CHANNELS {
            return Err(Failure::invalid(format!(
                "channels {channels}: a bank holds 1 to {HYSTCOMP_MAX_CHANNELS} channels"
            )));
        }
        if !models.is_aligned() {
            return Err(Failure::invalid("models is not aligned for pointers"));
        }
        let mut list = Vec::with_capacity(channels);
        for k in 0..channels {
            // SAFETY: `k < channels`, `models` valid for `channels` reads (the caller's
            // contract), non-NULL and aligned (checked).
            let m = unsafe { models.add(k).read() };
            // SAFETY: a live model handle or NULL (the caller's contract).
            let model = unsafe { model_arg(m) }.map_err(|_| {
                Failure::new(
                    HystcompStatus::NullPointer,
                    format!("models[{k}] is NULL; pass a live model handle for every channel"),
                )
            })?;
            list.push(Channel {
                name: format!("channel_{k}"),
                model: model.file.clone(),
            });
        }
        let set = ModelSet::new(None, list)?;
        // SAFETY: `2 * limits_len` doubles or NULL (the caller's contract).
        let limits = unsafe { limits_arg(limits, limits_len, channels) }?;
        let inner = ScaledBank::new(&set, method, limits.as_deref(), unstable)?;
        // SAFETY: `out` was checked non-NULL by `clear_out`.
        unsafe { put_handle(out, HystcompBank { inner }) };
        Ok(())
    })
}

/// Writes the number of channels to `*channels`.
///
/// # Safety
/// `h` must be a live handle or NULL; `channels` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_bank_channels(
    h: *const HystcompBank,
    channels: *mut usize,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract); only read.
        let b = unsafe { h.as_ref() }.ok_or_else(|| Failure::null("bank handle"))?;
        // SAFETY: valid for a write or NULL (checked by write_out).
        unsafe { crate::args::write_out(channels, b.inner.channels(), "channels") }
    })
}

/// One control tick: `v[c]` is the drive for the desired position `y_d[c]` of channel `c`,
/// `channels` values each (the bank's channel count; another count is refused). `y_d` and `v`
/// may be the same array (in place); they must not otherwise overlap.
///
/// Every `v[c]` lies within its channel's limits and is never NaN. A NaN or infinite `y_d[c]`
/// (or one so large that it overflows when normalised by the channel's scale) holds channel
/// `c`'s previous drive; the tick is still done for every channel and
/// `HYSTCOMP_STATUS_NON_FINITE_INPUT` is returned. Never allocates on success.
///
/// # Safety
/// `h` must be a live handle or NULL; `y_d` and `v` must point to `channels` doubles (or be
/// NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_bank_step(
    h: *mut HystcompBank,
    y_d: *const f64,
    v: *mut f64,
    channels: usize,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        let b = unsafe { handle(h, "bank handle") }?;
        // SAFETY: `channels` doubles each or NULL (the caller's contract).
        unsafe { tick(b, y_d, v, channels, 1) }
    })
}

/// A whole signal of `samples` ticks, row-major: `y_d[k * channels + c]` is channel `c` at
/// tick `k` (a C array `double y_d[samples][channels]`), and `v` the same for the drives; as
/// `samples` calls of `hystcomp_bank_step`. `y_d` and `v` may be the same array. With
/// `samples == 0` nothing is done and the arrays may be NULL.
///
/// # Safety
/// `h` must be a live handle or NULL; `y_d` and `v` must point to `samples * channels`
/// doubles (or be NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_bank_process(
    h: *mut HystcompBank,
    y_d: *const f64,
    v: *mut f64,
    samples: usize,
    channels: usize,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        let b = unsafe { handle(h, "bank handle") }?;
        if samples == 0 {
            return Ok(());
        }
        // SAFETY: `samples * channels` doubles each or NULL (the caller's contract).
        unsafe { tick(b, y_d, v, channels, samples) }
    })
}

/// `samples` ticks of `channels` values from `y_d` into `v`.
///
/// # Safety
/// `y_d` and `v` must be valid for `samples * channels` doubles, or NULL.
unsafe fn tick(
    b: &mut HystcompBank,
    y_d: *const f64,
    v: *mut f64,
    channels: usize,
    samples: usize,
) -> Result<(), Failure> {
    if channels != b.inner.channels() {
        return Err(Failure::invalid(format!(
            "channels {channels}, but the bank has {} channels",
            b.inner.channels()
        )));
    }
    if y_d.is_null() {
        return Err(Failure::null("y_d"));
    }
    if v.is_null() {
        return Err(Failure::null("v"));
    }
    let len = samples
        .checked_mul(channels)
        .ok_or_else(|| Failure::invalid(format!("samples {samples} is impossibly large")))?;
    check_array(y_d, len, "y_d")?;
    check_array(v, len, "v")?;
    let in_place = std::ptr::eq(y_d, v);
    let (mut count, mut first) = (0, 0);
    for k in 0..samples {
        let at = k * channels;
        if in_place {
            // SAFETY: `v` valid for `len` reads and writes (the caller's contract), non-NULL
            // and aligned (checked), `at + channels <= len`; no other reference to it.
            let values = unsafe { std::slice::from_raw_parts_mut(v.add(at), channels) };
            b.inner.step_in_place(values)?;
        } else {
            // SAFETY: as above, for `y_d` (reads) and `v` (writes), which do not overlap (the
            // caller's contract).
            let (input, output) = unsafe {
                (
                    std::slice::from_raw_parts(y_d.add(at), channels),
                    std::slice::from_raw_parts_mut(v.add(at), channels),
                )
            };
            b.inner.step(input, output)?;
        }
        let (c, f) = b.inner.held();
        if c > 0 && count == 0 {
            first = at + f;
        }
        count += c;
    }
    if count == 0 {
        Ok(())
    } else {
        Err(Failure::new(
            HystcompStatus::NonFiniteInput,
            format!(
                "{count} desired position(s) were NaN or infinite, or too large to normalise \
                 by their channel's scale (the first at index {first}: tick {}, channel {}); \
                 those channels held their previous drive",
                first / channels,
                first % channels
            ),
        ))
    }
}

/// Every channel back to its initial state (operators' memory zero, eq. (1); previous drive 0
/// clamped into the limits; diagnostics cleared).
///
/// # Safety
/// `h` must be a live handle or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_bank_reset(h: *mut HystcompBank) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        unsafe { handle(h, "bank handle") }?.inner.reset();
        Ok(())
    })
}

/// The bank's channel `channel`, or a failure naming the count.
fn channel_arg(b: &HystcompBank, channel: usize) -> Result<usize, Failure> {
    if channel < b.inner.channels() {
        Ok(channel)
    } else {
        Err(Failure::invalid(format!(
            "channel {channel} does not exist; the bank has channels 0 to {}",
            b.inner.channels() - 1
        )))
    }
}

/// Writes channel `channel`'s drive limits `[*v_min, *v_max]` (its model's voltage unit).
///
/// # Safety
/// `h` must be a live handle or NULL; `v_min` and `v_max` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_bank_limits(
    h: *const HystcompBank,
    channel: usize,
    v_min: *mut f64,
    v_max: *mut f64,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract); only read.
        let b = unsafe { h.as_ref() }.ok_or_else(|| Failure::null("bank handle"))?;
        let (lo, hi) = b.inner.limits(channel_arg(b, channel)?).unwrap_or_default();
        if v_max.is_null() {
            return Err(Failure::null("v_max"));
        }
        // SAFETY: valid for a write or NULL (checked by write_out).
        unsafe { crate::args::write_out(v_min, lo, "v_min") }?;
        // SAFETY: as above.
        unsafe { crate::args::write_out(v_max, hi, "v_max") }
    })
}

/// Writes channel `channel`'s counters since the last reset: ticks whose desired position
/// could not be reached within the limits (`*saturated`), ticks a delayed loop drove to a
/// limit although the position was reachable (`*loop_saturated`), NaN or infinite desired
/// positions (`*non_finite`). Any pointer may be NULL when that counter is not wanted.
///
/// # Safety
/// `h` must be a live handle or NULL; the counters valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_bank_diagnostics(
    h: *const HystcompBank,
    channel: usize,
    saturated: *mut u64,
    loop_saturated: *mut u64,
    non_finite: *mut u64,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract); only read.
        let b = unsafe { h.as_ref() }.ok_or_else(|| Failure::null("bank handle"))?;
        let d = b
            .inner
            .diagnostics(channel_arg(b, channel)?)
            .unwrap_or_default();
        for (out, value) in [
            (saturated, d.saturated),
            (loop_saturated, d.loop_saturated),
            (non_finite, d.non_finite),
        ] {
            if !out.is_null() {
                // SAFETY: non-NULL, valid for a write (the caller's contract).
                unsafe { out.write(value) };
            }
        }
        Ok(())
    })
}

/// Releases a bank. NULL is accepted (and ignored); a handle must not be used after, nor
/// freed twice.
///
/// # Safety
/// `h` must be a live handle from this library or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_bank_free(h: *mut HystcompBank) {
    if h.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: a live handle made by `Box::into_raw` in this library, freed once (the
        // caller's contract).
        drop(unsafe { Box::from_raw(h) });
    }));
}
