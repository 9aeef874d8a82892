//! The machine's memory, as a run sees it: how much a run may need when `max-memory` is not
//! given, and the peak it used.

use std::path::{Path, PathBuf};

/// The memory a run may need when `max-memory` is not given: half the machine's physical
/// memory, and no more than the process may have (its address-space limit, `ulimit -v`,
/// less room for code, thread stacks and the allocator's reservations; a cgroup's
/// limit, as containers and farm schedulers set it: [`cgroup_limit`]). 8 GiB where none can
/// be read.
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
    let read = |path: &Path| std::fs::read_to_string(path).ok();
    let own = read(Path::new("/proc/self/cgroup")).unwrap_or_default();
    let mounts = read(Path::new("/proc/self/mountinfo")).unwrap_or_default();
    if let Some((cgroup, file)) = cgroup_limit(&own, &mounts, read) {
        if cgroup < limit {
            limit = cgroup;
            said = format!(
                "the cgroup's limit of {} MiB ({})",
                mib(cgroup),
                file.display()
            );
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

/// The smallest memory limit of the process's cgroup and the cgroups above it, and the file
/// that set it, from `/proc/self/cgroup` (`own`) and `/proc/self/mountinfo` (`mounts`), with
/// `read` reading a file. Both hierarchies: cgroup v2's `memory.max` (`max`: none) and v1's
/// `memory.limit_in_bytes` (values of 2⁶² and above: none). The process's cgroup is found
/// under the hierarchy's mount, so a job placed in a cgroup of its own (a Slurm task, a
/// systemd scope) is judged by its own limit, not by the root's, which has none; inside a
/// cgroup namespace the mount is the process's own cgroup.
fn cgroup_limit(
    own: &str,
    mounts: &str,
    read: impl Fn(&Path) -> Option<String>,
) -> Option<(u64, PathBuf)> {
    let mut best: Option<(u64, PathBuf)> = None;
    for line in own.lines() {
        let mut fields = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(path)) =
            (fields.next(), fields.next(), fields.next())
        else {
            continue;
        };
        let (v2, file) = match controllers {
            "" => (true, "memory.max"),
            c if c.split(',').any(|c| c == "memory") => (false, "memory.limit_in_bytes"),
            _ => continue,
        };
        let Some((root, mount)) = mount_of(mounts, v2) else {
            continue;
        };
        // The cgroup's folder under the mount: its path less the mount's root (a namespace's
        // mount is the cgroup itself, its path then "/").
        let relative = path.strip_prefix(root.as_str()).unwrap_or("");
        let mut folder = mount.clone();
        folder.extend(relative.split('/').filter(|p| !p.is_empty() && *p != ".."));
        loop {
            let at = folder.join(file);
            let value = read(&at).and_then(|t| t.trim().parse::<u64>().ok());
            if let Some(value) = value.filter(|&v| v < 1 << 62) {
                if best.as_ref().is_none_or(|(b, _)| value < *b) {
                    best = Some((value, at));
                }
            }
            if folder == mount || !folder.pop() {
                break;
            }
        }
    }
    best
}

/// The root and the mount point of the memory hierarchy in `mounts` (`/proc/self/mountinfo`):
/// cgroup v2's (`v2`), or v1's with the memory controller.
fn mount_of(mounts: &str, v2: bool) -> Option<(String, PathBuf)> {
    mounts.lines().find_map(|line| {
        let (ours, theirs) = line.split_once(" - ")?;
        let ours: Vec<&str> = ours.split(' ').collect();
        let mut theirs = theirs.split(' ');
        let kind = theirs.next()?;
        let options = theirs.nth(1).unwrap_or("");
        let matches = if v2 {
            kind == "cgroup2"
        } else {
            kind == "cgroup" && options.split(',').any(|o| o == "memory")
        };
        let unescape = |s: &str| s.replace("\\040", " ");
        (matches && ours.len() >= 5).then(|| (unescape(ours[3]), PathBuf::from(unescape(ours[4]))))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn files(entries: &[(&str, &str)]) -> impl Fn(&Path) -> Option<String> {
        let map: HashMap<PathBuf, String> = (entries.iter())
            .map(|(p, v)| (PathBuf::from(p), v.to_string()))
            .collect();
        move |p: &Path| map.get(p).cloned()
    }

    const V2_MOUNT: &str = "29 23 0:26 / /sys/fs/cgroup rw,nosuid - cgroup2 cgroup2 rw,nsdelegate";

    #[test]
    fn a_slurm_task_s_own_cgroup_limit_is_read_under_the_root() {
        // A Slurm step under cgroup v2 without a namespace: the root has no memory.max; the
        // job's folder has 4 GiB and the step's none.
        let own = "0::/system.slice/slurmstepd.scope/job_42/step_0/user/task_0\n";
        let job = "/sys/fs/cgroup/system.slice/slurmstepd.scope/job_42/memory.max";
        let read = files(&[
            (job, "4294967296\n"),
            (
                "/sys/fs/cgroup/system.slice/slurmstepd.scope/job_42/step_0/user/task_0/memory.max",
                "max\n",
            ),
        ]);
        let (limit, file) = cgroup_limit(own, V2_MOUNT, read).unwrap();
        assert_eq!(limit, 4 << 30);
        assert_eq!(file, PathBuf::from(job));
    }

    #[test]
    fn a_cgroup_v1_memory_limit_is_read() {
        let own = "9:name=systemd:/\n4:memory:/farm/job7\n0::/\n";
        let mounts = "35 31 0:32 / /sys/fs/cgroup/memory rw,relatime - cgroup cgroup rw,memory\n\
                      41 31 0:38 / /sys/fs/cgroup/unified rw,relatime - cgroup2 cgroup2 rw";
        let read = files(&[
            (
                "/sys/fs/cgroup/memory/memory.limit_in_bytes",
                "9223372036854771712",
            ),
            (
                "/sys/fs/cgroup/memory/farm/memory.limit_in_bytes",
                "8589934592",
            ),
            (
                "/sys/fs/cgroup/memory/farm/job7/memory.limit_in_bytes",
                "2147483648",
            ),
        ]);
        let (limit, _) = cgroup_limit(own, mounts, read).unwrap();
        assert_eq!(limit, 2 << 30);
    }

    #[test]
    fn inside_a_namespace_the_mount_is_the_cgroup_and_unlimited_is_none() {
        // A container's namespace: its own cgroup is mounted at /sys/fs/cgroup, its path "/".
        let read = files(&[("/sys/fs/cgroup/memory.max", "1073741824")]);
        assert_eq!(cgroup_limit("0::/\n", V2_MOUNT, &read).unwrap().0, 1 << 30);
        let read = files(&[("/sys/fs/cgroup/memory.max", "max")]);
        assert_eq!(cgroup_limit("0::/\n", V2_MOUNT, read), None);
        // No cgroup file at all (another system): nothing.
        assert_eq!(cgroup_limit("", "", files(&[])), None);
    }
}
