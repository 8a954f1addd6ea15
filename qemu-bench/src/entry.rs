//! The entry point every binary of this package shares.

/// Declares the harness modules ([`counter`](crate::counter), [`mcu`](crate::mcu)) and the
/// binary's own `$module`s, bare-metal only, and a `main` that runs `$run` under
/// [`mcu::run`](crate::mcu::run); on the host, `main` does nothing (the benchmarks run only in
/// QEMU).
macro_rules! bench_main {
    ($($module:ident),+ => $run:path) => {
        #[cfg(target_os = "none")]
        mod counter;
        #[cfg(target_os = "none")]
        mod mcu;
        $(
            #[cfg(target_os = "none")]
            mod $module;
        )+

        #[cfg(target_os = "none")]
        #[cortex_m_rt::entry]
        fn main() -> ! {
            mcu::run($run)
        }

        /// Host builds: nothing to run (the benchmark runs only in QEMU).
        #[cfg(not(target_os = "none"))]
        fn main() {}
    };
}
