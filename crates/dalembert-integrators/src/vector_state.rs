//! The x86-64 vector unit's "dirty upper state": after code that writes the upper halves of the
//! 256/512-bit registers without a closing `vzeroupper`, every legacy SSE instruction of the
//! baseline build (this crate's and the models' code) pays a merge dependency. Measured on the
//! planar chain of 64 links (augmented, RK4, 1 ms, 5 s): 725 ms in the integration loop when the
//! state was left dirty by the scene's setup, 310 ms after one `vzeroupper` (and the same 310 ms
//! when setup happened to end with one, as `dalembert simulate`'s structure analysis did, which is
//! why `simulate` and `trade` timed the same run 2.3× apart). Nothing in the stepping loop of the
//! sparse back ends clears it, so the driver clears it before the loop and after each observer
//! call (user code).

/// Clears the upper halves of the vector registers where the CPU has AVX; nothing elsewhere.
#[inline]
pub(crate) fn clear_upper_state() {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU supports AVX (checked just above), which `vzeroupper` requires; the
        // instruction changes no state a Rust program relies on between calls.
        unsafe { std::arch::x86_64::_mm256_zeroupper() };
    }
}
