//! Every process-wide setting of mra, and the only place that reads the environment.
//!
//! None of these settings changes a result: every CPU level, engine and page size gives
//! the same bits. They change speed and memory only. A library user sets them with
//! [`set`] before the first transform (or leaves them to the environment, read once by
//! [`get`]); the command line reads the environment.
//!
//! | variable | values | effect |
//! |---|---|---|
//! | `MRA_CPU` | `scalar`, `avx2` (unset: the widest the CPU runs) | caps the kernels' build ([`CpuLevel`]) |
//! | `MRA_ENGINE` | `levels`, `axis`, `cascade` (unset: the fused cascade) | picks how pyramids run ([`EngineChoice`]) |
//! | `MRA_HUGE_PAGES` | `off` or `0` (unset: on) | the engine's own large buffers advised onto 2 MB pages (Linux) |
//! | `MRA_MAX_BYTES` | a byte count: `1048576`, `512M`, `8G` (unset: 8 GiB) | the memory budget a declared size must fit before anything is allocated ([`crate::limits::Limits`]) |
//!
//! (`MRA_CORPUS`, `MRA_REQUIRE_CORPUS` and `MRA_BENCH_QUICK` are read by the tests and
//! benches only, never by the library.)

use std::sync::OnceLock;

/// The builds of the kernels, narrowest first. All give the same bits: each output's
/// taps summed as `scheme::sparse::sum_terms` says (its FMAs in software in the scalar
/// build).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum CpuLevel {
    /// Plain loops (whatever the compiler makes of them for the baseline target).
    Scalar,
    /// 256-bit vectors (AVX2 with FMA).
    Avx2,
    /// 512-bit vectors for the combines (the rest as [`CpuLevel::Avx2`]).
    Avx512,
}

impl CpuLevel {
    /// The widest build this CPU runs, capped by [`Tuning::cpu_cap`]; worked out once.
    pub fn detected() -> CpuLevel {
        static LEVEL: OnceLock<CpuLevel> = OnceLock::new();
        *LEVEL.get_or_init(|| CpuLevel::widest().min(get().cpu_cap))
    }

    /// The widest build this CPU runs, whatever the settings.
    pub fn widest() -> CpuLevel {
        #[cfg(target_arch = "x86_64")]
        {
            let fma = std::arch::is_x86_feature_detected!("fma");
            if fma && std::arch::is_x86_feature_detected!("avx512f") {
                CpuLevel::Avx512
            } else if fma && std::arch::is_x86_feature_detected!("avx2") {
                CpuLevel::Avx2
            } else {
                CpuLevel::Scalar
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        CpuLevel::Scalar
    }

    /// Every build this CPU runs, up to [`CpuLevel::detected`] (tests compare them).
    pub fn available() -> Vec<CpuLevel> {
        [CpuLevel::Scalar, CpuLevel::Avx2, CpuLevel::Avx512]
            .into_iter()
            .filter(|&s| s <= CpuLevel::detected())
            .collect()
    }
}

/// How pyramids run when the caller does not pick (`tensor::Engine`; all give the same
/// bits).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum EngineChoice {
    /// The fused cascade (`Engine::Fused`).
    #[default]
    Fused,
    /// Level by level (`Engine::FusedLevels`).
    Levels,
    /// Axis by axis (`Engine::AxisByAxis`).
    Axis,
    /// The cascade with a part per thread, volumes included (`Engine::CascadeParts`).
    Cascade,
}

/// The process-wide settings (see the module's table).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tuning {
    /// The widest kernel build used (`MRA_CPU`).
    pub cpu_cap: CpuLevel,
    /// The engine of `tensor::analyze` / `synthesize` (`MRA_ENGINE`).
    pub engine: EngineChoice,
    /// Whether the engine advises its large buffers onto huge pages (`MRA_HUGE_PAGES`).
    pub huge_pages: bool,
}

impl Default for Tuning {
    /// The widest build, the fused engine, huge pages on (no environment read).
    fn default() -> Self {
        Tuning {
            cpu_cap: CpuLevel::Avx512,
            engine: EngineChoice::Fused,
            huge_pages: true,
        }
    }
}

impl Tuning {
    /// The settings the environment asks for (values not listed in the module's table
    /// leave the default).
    pub fn from_env() -> Tuning {
        let var = |name: &str| std::env::var(name).ok();
        let d = Tuning::default();
        Tuning {
            cpu_cap: match var("MRA_CPU").as_deref() {
                Some("scalar") => CpuLevel::Scalar,
                Some("avx2") => CpuLevel::Avx2,
                _ => d.cpu_cap,
            },
            engine: match var("MRA_ENGINE").as_deref() {
                Some("axis") => EngineChoice::Axis,
                Some("levels") => EngineChoice::Levels,
                Some("cascade") => EngineChoice::Cascade,
                _ => d.engine,
            },
            huge_pages: !matches!(var("MRA_HUGE_PAGES").as_deref(), Some("off" | "0")),
        }
    }
}

static SETTINGS: OnceLock<Tuning> = OnceLock::new();

/// The settings in force: those given to [`set`], else the environment's
/// ([`Tuning::from_env`]), fixed at the first call.
pub fn get() -> &'static Tuning {
    SETTINGS.get_or_init(Tuning::from_env)
}

/// Fix the settings before anything reads them; `Err` with the settings in force when
/// they were already fixed (by an earlier [`set`] or [`get`]).
pub fn set(t: Tuning) -> Result<(), Tuning> {
    SETTINGS.set(t).map_err(|_| *get())
}

/// `MRA_MAX_BYTES` as set in the environment (parsed by [`crate::limits::Limits::from_env`]).
pub fn max_bytes_var() -> Option<String> {
    std::env::var("MRA_MAX_BYTES").ok()
}

/// How glibc's allocator keeps or returns freed memory (`mallopt`), one policy per
/// process, set by [`use_allocator`] before threads allocate. Each command picks the one
/// its arrays' lifetimes call for; off Linux with glibc the allocator keeps its own.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Allocator {
    /// Blocks from 1 MiB on mapped on their own and unmapped when freed (the command
    /// line's default). glibc otherwise raises its mapping threshold after each large free
    /// (up to 32 MiB) and serves later buffers from its heap, which keeps what they freed:
    /// a 256³ u16 encode at `--bpp 1` held 101 MB for 86 MB of live buffers, 93 MB with the
    /// threshold fixed (the same bytes; 0.1 s more of system time for the page faults).
    /// The heap keeps up to 8 MiB of free space at its top (glibc trims from 128 KiB):
    /// the small buffers a code-block decode makes and frees by the thousand otherwise
    /// give the heap's top pages back and fault them in again (a flower decode at
    /// effort 1: 67,800 page faults, 39,200 with the 8 MiB; the same peak).
    ReturnLarge,
    /// Freed buffers of up to 32 MiB kept in the heap (blocks from 32 MiB on mapped
    /// directly, the heap trimmed from 256 MiB of free space on): a command that allocates
    /// and frees image-sized arrays a dozen times (the refined area upscaler) otherwise
    /// pays a page fault per fresh page, a third of its time on a Kodak image. Larger
    /// arrays (volumes) are still mapped directly, so peak memory is unchanged.
    KeepFreed,
    /// Every allocation from the heap and nothing given back (no direct mappings, no
    /// trimming), so a large buffer freed early is reused by the next ones instead of fresh
    /// pages the kernel must clear: for one-shot commands whose arrays are freed before the
    /// next are made (the volume isosurface: the compressed file, the grid, the mesh and its
    /// bytes). On a 256³ field the system time falls from 0.36 s to 0.13 s and the peak rises
    /// by what is freed before it is reused (143 → 175 MB).
    ReuseFreed,
}

/// Sets the allocator's policy ([`Allocator`]); call it before threads allocate much.
pub fn use_allocator(policy: Allocator) {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn mallopt(param: i32, value: i32) -> i32;
        }
        // <malloc.h>
        const M_TRIM_THRESHOLD: i32 = -1;
        const M_MMAP_THRESHOLD: i32 = -3;
        const M_MMAP_MAX: i32 = -4;
        let settings: &[(i32, i32)] = match policy {
            Allocator::ReturnLarge => &[(M_MMAP_THRESHOLD, 1 << 20), (M_TRIM_THRESHOLD, 8 << 20)],
            Allocator::KeepFreed => &[(M_MMAP_THRESHOLD, 32 << 20), (M_TRIM_THRESHOLD, 256 << 20)],
            Allocator::ReuseFreed => &[(M_MMAP_MAX, 0), (M_TRIM_THRESHOLD, i32::MAX)],
        };
        for &(param, value) in settings {
            // SAFETY: glibc's mallopt only changes allocator thresholds; a refused setting
            // (result 0) leaves the allocator's own, which is still correct.
            unsafe {
                mallopt(param, value);
            }
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = policy;
}

/// Gives the pages of freed memory inside the allocator's heaps back to the system
/// (glibc's `malloc_trim(0)`: whole free pages of every arena), for a command about to
/// make its largest buffers after freeing many small ones (the `--max-error` encoder
/// between its bases and residuals); nothing elsewhere.
pub fn release_freed() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn malloc_trim(pad: usize) -> i32;
        }
        // SAFETY: malloc_trim only returns free pages of the allocator's own heaps to
        // the system; live allocations are untouched.
        unsafe {
            malloc_trim(0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_settings_read_no_environment() {
        let d = Tuning::default();
        assert_eq!(d.cpu_cap, CpuLevel::Avx512);
        assert_eq!(d.engine, EngineChoice::Fused);
        assert!(d.huge_pages);
    }

    #[test]
    fn cpu_levels_are_ordered_narrowest_first() {
        assert!(CpuLevel::Scalar < CpuLevel::Avx2 && CpuLevel::Avx2 < CpuLevel::Avx512);
        let a = CpuLevel::available();
        assert_eq!(a[0], CpuLevel::Scalar);
        assert!(a.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(*a.last().unwrap(), CpuLevel::detected());
    }
}
