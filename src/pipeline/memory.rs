//! The machine's memory, as a run sees it: how much a run may need when `max-memory` is not
//! given, and the peak it used.

/// The memory a run may need when `max-memory` is not given: half the machine's physical
/// memory, and no more than the process may have (its address-space limit, `ulimit -v`,
/// less room for code, thread stacks and the allocator's reservations; a cgroup's
/// `memory.max`, as containers and farm schedulers set it). 8 GiB where none can be read.
pub fn memory_limit() -> u64 {
    memory_limit_said().0
}

/// [`memory_limit`], and which limit set it, in words (for a message that refuses a frame).
pub fn memory_limit_said() -> (u64, String) {
    let mib = |bytes: u64| bytes >> 20;
    let mut limit = physical_memory().map_or(8 << 30, |total| total / 2);
    let mut said = "half the machine's memory".to_string();
    #[cfg(unix)]
    if let Ok((soft, _)) = nix::sys::resource::getrlimit(nix::sys::resource::Resource::RLIMIT_AS) {
        if soft != nix::sys::resource::RLIM_INFINITY {
            // Under a tight limit the room shrinks with it (the allocator then reserves
            // less): all of 768 MiB under a limit of 700 MB left 0 MiB for frames that fit.
            let room = ADDRESS_SPACE_ROOM.min(soft / 3);
            if soft.saturating_sub(room) < limit {
                limit = soft.saturating_sub(room);
                said = format!(
                    "the process's address-space limit (ulimit -v) of {} MiB, less {} MiB \
                     for the program",
                    mib(soft),
                    mib(room)
                );
            }
        }
    }
    if let Some(cgroup) = std::fs::read_to_string("/sys/fs/cgroup/memory.max")
        .ok()
        .and_then(|t| t.trim().parse::<u64>().ok())
    {
        if cgroup < limit {
            limit = cgroup;
            said = format!("the cgroup's memory.max of {} MiB", mib(cgroup));
        }
    }
    (limit, said)
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
