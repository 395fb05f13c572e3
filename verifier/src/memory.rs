//! What the process may use and what it uses, read from Linux's `/proc` and cgroup files.
//! Elsewhere these answer `None` and the explorer relies on its own accounting.

use std::cell::Cell;
use std::fs;

thread_local! {
    /// Whether the allocations of this thread may fail now without ending the process.
    static FALLIBLE: Cell<bool> = const { Cell::new(false) };
}

/// Runs `f`, whose allocations may be refused and are handled (a `try_reserve`): a global
/// allocator that ends the process on a refused allocation (the `bip` binary's) lets
/// these return their error ([`allocation_may_fail`]).
pub fn fallibly<T>(f: impl FnOnce() -> T) -> T {
    FALLIBLE.with(|c| c.set(true));
    let out = f();
    FALLIBLE.with(|c| c.set(false));
    out
}

/// True inside [`fallibly`] on this thread.
pub fn allocation_may_fail() -> bool {
    FALLIBLE.with(Cell::get)
}

/// The memory a run may use when the user sets no limit: 3/4 of the smallest of what is
/// available now (the system's available memory), what the cgroup still allows (v2's
/// `memory.max`, v1's `memory.limit_in_bytes`, less what the cgroup uses) and what the
/// address-space limit (`ulimit -v`) still allows, so that the run ends as inconclusive
/// before the operating system would have to kill it or an allocation would fail.
pub fn default_limit() -> Option<u64> {
    let available = meminfo_kib("MemAvailable:").map(|k| k * 1024);
    let base = [available, cgroup_allowance(), address_space_allowance()]
        .into_iter()
        .flatten()
        .min()?;
    Some(base / 4 * 3)
}

/// Address space that each thread may reserve beyond what it uses: its stack and glibc's
/// malloc arena (64 MiB reserved per arena, one per thread up to eight per core).
const THREAD_RESERVE: u64 = 72 << 20;

/// What the address-space limit (RLIMIT_AS, `ulimit -v`) leaves for the run's data: the
/// limit less what the process maps now (its libraries, z3 among them, and its heap) and a
/// reserve for each thread the run may start (the workers, the watchdog, the main thread).
/// The limit counts virtual memory, which grows before the resident memory the watch
/// measures does.
fn address_space_allowance() -> Option<u64> {
    let limits = fs::read_to_string("/proc/self/limits").ok()?;
    let line = limits
        .lines()
        .find_map(|l| l.strip_prefix("Max address space"))?;
    // "unlimited" does not parse: no limit
    let soft: u64 = line.split_whitespace().next()?.parse().ok()?;
    let mapped = status_kib("VmSize:")? * 1024;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()) as u64 + 2;
    Some(
        soft.saturating_sub(mapped)
            .saturating_sub(threads * THREAD_RESERVE),
    )
}

/// Resident memory of this process now.
pub fn resident_bytes() -> Option<u64> {
    let statm = fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * page_size())
}

/// Peak resident memory of this process.
pub fn peak_resident_bytes() -> Option<u64> {
    Some(status_kib("VmHWM:")? * 1024)
}

/// A figure of `/proc/self/status`, in KiB.
fn status_kib(key: &str) -> Option<u64> {
    let status = fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn page_size() -> u64 {
    // statm counts pages; 4 KiB on the platforms bip targets. /proc/self/smaps would say
    // for sure, but reading it is slow.
    4096
}

fn meminfo_kib(key: &str) -> Option<u64> {
    let info = fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with(key))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// What this process's cgroup still allows, if it has a limit: `memory.max -
/// memory.current` (cgroup v2), or `memory.limit_in_bytes - memory.usage_in_bytes` (v1).
fn cgroup_allowance() -> Option<u64> {
    let cgroup = fs::read_to_string("/proc/self/cgroup").ok()?;
    let v2 = || {
        let path = cgroup.lines().find_map(|l| l.strip_prefix("0::"))?;
        let dir = format!("/sys/fs/cgroup{}", path.trim_end());
        allowance(&dir, "memory.max", "memory.current")
    };
    let v1 = || {
        // `N:memory:/path`, or the controller among others (`N:cpu,memory:/path`)
        let path = cgroup.lines().find_map(|l| {
            let mut parts = l.splitn(3, ':');
            let _ = parts.next()?;
            let controllers = parts.next()?;
            let path = parts.next()?;
            controllers
                .split(',')
                .any(|c| c == "memory")
                .then_some(path)
        })?;
        let dir = format!("/sys/fs/cgroup/memory{}", path.trim_end());
        allowance(&dir, "memory.limit_in_bytes", "memory.usage_in_bytes")
    };
    v2().or_else(v1)
}

/// `limit - usage` from two files of a cgroup directory; `None` without a limit (v2
/// writes `max`, v1 a number near 2^63).
fn allowance(dir: &str, limit: &str, usage: &str) -> Option<u64> {
    let read = |f: &str| -> Option<u64> {
        fs::read_to_string(format!("{dir}/{f}"))
            .ok()?
            .trim()
            .parse()
            .ok()
    };
    let max = read(limit).filter(|&m| m < 1 << 62)?;
    Some(max.saturating_sub(read(usage).unwrap_or(0)))
}

/// Parses a size as the command line takes it: `1000000`, `512K`, `300M`, `4G`, `1T`
/// (binary units; an optional `B` or `iB` suffix is accepted).
pub fn parse_size(text: &str) -> Result<u64, String> {
    let lower = text.trim().to_ascii_lowercase();
    let t = lower
        .strip_suffix("ib")
        .or_else(|| lower.strip_suffix('b'))
        .unwrap_or(&lower);
    let (digits, unit) = match t.char_indices().find(|(_, c)| c.is_ascii_alphabetic()) {
        Some((i, _)) => (&t[..i], &t[i..]),
        None => (t, ""),
    };
    let shift = match unit.to_ascii_uppercase().as_str() {
        "" => 0,
        "K" => 10,
        "M" => 20,
        "G" => 30,
        "T" => 40,
        _ => return Err(format!("`{text}`: unknown unit (use K, M, G or T)")),
    };
    let value: f64 = digits
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a size (like 512M or 4G)"))?;
    if !value.is_finite() || value < 0.0 {
        return Err(format!("`{text}` is not a size (like 512M or 4G)"));
    }
    let bytes = value * (1u64 << shift) as f64;
    if bytes >= u64::MAX as f64 {
        return Err(format!("`{text}` is too large"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_units() {
        assert_eq!(parse_size("1000"), Ok(1000));
        assert_eq!(parse_size("512K"), Ok(512 << 10));
        assert_eq!(parse_size("1.5G"), Ok(3 << 29));
        assert_eq!(parse_size("2GiB"), Ok(2 << 30));
        assert_eq!(parse_size("300mb"), Ok(300 << 20));
        assert!(parse_size("12X").is_err());
        assert!(parse_size("-1M").is_err());
        assert!(parse_size("").is_err());
    }

    #[test]
    fn this_process_has_a_size_on_linux() {
        if cfg!(target_os = "linux") {
            assert!(resident_bytes().is_some_and(|b| b > 0));
            assert!(peak_resident_bytes().is_some_and(|b| b > 0));
            assert!(default_limit().is_some_and(|b| b > 0));
        }
    }
}
