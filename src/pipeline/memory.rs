//! The machine's memory, as a run sees it: how much a run may need when `max-memory` is not
//! given, and the peak it used.

/// The memory a run may need when `max-memory` is not given: half the machine's physical
/// memory, and no more than the process may have (its address-space limit, `ulimit -v`,
/// less room for code, thread stacks and the allocator's reservations; a cgroup's
/// `memory.max`, as containers and farm schedulers set it). 8 GiB where none can be read.
pub fn memory_limit() -> u64 {
    let mut limit = physical_memory().map_or(8 << 30, |total| total / 2);
    #[cfg(unix)]
    if let Ok((soft, _)) = nix::sys::resource::getrlimit(nix::sys::resource::Resource::RLIMIT_AS) {
        if soft != nix::sys::resource::RLIM_INFINITY {
            limit = limit.min(soft.saturating_sub(ADDRESS_SPACE_ROOM));
        }
    }
    if let Some(cgroup) = std::fs::read_to_string("/sys/fs/cgroup/memory.max")
        .ok()
        .and_then(|t| t.trim().parse::<u64>().ok())
    {
        limit = limit.min(cgroup);
    }
    limit
}

/// What the address space holds besides the frames' memory: the program, thread stacks, the
/// allocator's per-thread arenas (reserved, not used), the GPU driver's mappings.
const ADDRESS_SPACE_ROOM: u64 = 768 << 20;

/// Physical memory (Linux: /proc/meminfo's MemTotal); `None` elsewhere.
fn physical_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib << 10)
}

/// Peak resident set size from /proc (Linux); `None` elsewhere.
pub fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}
