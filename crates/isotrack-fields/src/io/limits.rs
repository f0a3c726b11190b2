//! Limits on what a loader reads: regular files only, at most a size, and a series no larger
//! than the memory this process may use.

use super::error::LoadError;
use std::path::Path;

/// The largest grid file read, bytes (4 GiB: a grid of [`crate::grid::MAX_NODES`] float64
/// values is 2 GiB; text formats take about twice that).
pub const MAX_GRID_FILE_BYTES: u64 = 4 << 30;

/// Opens an input file for reading, refusing what is not a regular file (a FIFO, a device, a
/// directory) without blocking: the type is looked up (`stat`) before the file is opened,
/// since opening a FIFO for reading waits for a writer, possibly for ever. On Unix the open
/// itself is non-blocking too (`O_NONBLOCK`, which regular files ignore), and the opened file
/// is checked again, so a FIFO swapped in between the two is refused rather than waited on. A
/// "regular file" the kernel makes up as it is read (`/proc`, `/sys`: the open file's
/// filesystem, [`refuse_kernel_pseudo_file`]) is refused before a byte is read.
/// Every input path of isotrack opens its files through here.
pub fn open_regular(path: &Path) -> std::io::Result<std::fs::File> {
    let not_regular = || {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file (a device, pipe or directory)",
        )
    };
    if !std::fs::metadata(path)?.is_file() {
        return Err(not_regular());
    }
    let mut opts = std::fs::OpenOptions::new();
    opts.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        opts.custom_flags(libc::O_NONBLOCK);
    }
    let f = opts.open(path)?;
    if !f.metadata()?.is_file() {
        return Err(not_regular());
    }
    refuse_kernel_pseudo_file(&f)?;
    Ok(f)
}

/// The filesystems whose "regular files" the kernel makes up as they are read (statfs(2)'s
/// `f_type`): `/proc` (`PROC_SUPER_MAGIC`), `/sys` (`SYSFS_MAGIC`), debugfs, tracefs,
/// securityfs. Their files declare a size of 0 (or 4096) whatever they produce: no data.
#[cfg(target_os = "linux")]
const KERNEL_PSEUDO_FILESYSTEMS: [(i64, &str); 5] = [
    (0x9fa0, "/proc"),
    (0x6265_6572, "/sys"),
    (0x6462_6720, "debugfs"),
    (0x7472_6163, "tracefs"),
    (0x7363_6673, "securityfs"),
];

/// Refuses open file `f` when it lives on a kernel pseudo-filesystem
/// ([`KERNEL_PSEUDO_FILESYSTEMS`], asked with `fstatfs` on the open file: no read, no wait),
/// before a byte of it is read (issue 30: `/proc/self/pagemap` as a field's grid was read to
/// the 4 GiB size cap, 7 s, before the kernel's EINVAL).
fn refuse_kernel_pseudo_file(f: &std::fs::File) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::io::AsRawFd;
        // SAFETY: `st` is a plain C struct that fstatfs fills; the descriptor is `f`'s, open.
        let mut st: libc::statfs = unsafe { std::mem::zeroed() };
        if unsafe { libc::fstatfs(f.as_raw_fd(), &mut st) } == 0 {
            #[allow(clippy::unnecessary_cast)]
            let kind = st.f_type as i64;
            if let Some((_, fs)) = KERNEL_PSEUDO_FILESYSTEMS.iter().find(|(m, _)| *m == kind) {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    format!(
                        "a kernel pseudo-file on {fs}, not data (its content is made up by the kernel as it is read)"
                    ),
                ));
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = f;
    Ok(())
}

/// Reads a whole file of at most `max_bytes`, refusing what is not a regular file (a FIFO,
/// `/dev/zero`, a directory) before reading a byte: such "files" never end, or end anywhere.
/// The size is checked from the metadata and again on the bytes actually read (a `/proc` file
/// that declares 0 bytes, or a file that grows, is stopped with an error one byte past the
/// limit, not read on). The buffer is allocated fallibly ([`whole_file_buffer`]): a file
/// larger than the memory this process may use is an `OutOfMemory` error naming the bytes
/// wanted, never an abort (att43-5: a 3 GiB grid under `ulimit -v` aborted with "memory
/// allocation of 3221225472 bytes failed").
pub fn read_limited(path: &Path, max_bytes: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let f = open_regular(path)?;
    let meta = f.metadata()?;
    let too_big = |n: u64| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("{n} bytes is more than the {max_bytes} this reader accepts"),
        )
    };
    if meta.len() > max_bytes {
        return Err(too_big(meta.len()));
    }
    let mut bytes = whole_file_buffer(meta.len(), memory_budget_bytes())?;
    // (`read_to_end` grows the buffer fallibly too, an `OutOfMemory` error, for a file that
    // declares fewer bytes than it holds.)
    f.take(max_bytes + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

/// An empty buffer with room for a file's `len` bytes, allocated fallibly: `len` beyond
/// `budget_bytes` (the memory this process may use, [`memory_budget_bytes`]) is refused before
/// anything is allocated, and an allocation the system refuses is an error too, never an abort.
/// Either is an `OutOfMemory` error naming the bytes wanted and the memory
/// ([`LoadError::cannot_read`] gives it exit 65, as the Limits table's memory check).
pub(crate) fn whole_file_buffer(len: u64, budget_bytes: Option<u64>) -> std::io::Result<Vec<u8>> {
    let gib = |b: u64| b as f64 / f64::from(1u32 << 30);
    let no_room = |why: String| {
        std::io::Error::new(
            std::io::ErrorKind::OutOfMemory,
            format!("its {len} bytes ({:.2} GiB) are read whole into memory (to hash the very bytes parsed), and {why}", gib(len)),
        )
    };
    if let Some(b) = budget_bytes.filter(|b| len > *b) {
        return Err(no_room(format!(
            "the memory this process may use ({:.2} GiB: MemAvailable, a cgroup limit or `ulimit -v`) holds fewer",
            gib(b)
        )));
    }
    let mut bytes = Vec::new();
    let room = usize::try_from(len)
        .map_err(|_| ())
        .and_then(|n| bytes.try_reserve_exact(n).map_err(|_| ()));
    room.map_err(|()| no_room("the system refused to allocate that much memory".into()))?;
    Ok(bytes)
}

/// A regular file read as a stream, at most `max_bytes` of it: a read past the limit is an
/// error (`InvalidData`), never a silent cut. The limit counts the bytes actually read, not the
/// size the file declares: a `/proc` file declares 0 bytes and can produce gigabytes
/// (`/proc/self/pagemap`), and a file can grow while it is read.
#[derive(Debug)]
pub struct LimitedReader {
    inner: std::fs::File,
    left: u64,
    max_bytes: u64,
}

impl LimitedReader {
    /// The limit this reader enforces, bytes.
    pub fn max_bytes(&self) -> u64 {
        self.max_bytes
    }
}

impl std::io::Read for LimitedReader {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        if self.left == 0 {
            // At the limit: one more byte means the file is longer than allowed.
            let mut probe = [0u8; 1];
            return match self.inner.read(&mut probe)? {
                0 => Ok(0),
                _ => Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("more than the {} bytes this reader accepts", self.max_bytes),
                )),
            };
        }
        let n = buf
            .len()
            .min(usize::try_from(self.left).unwrap_or(usize::MAX));
        let got = self.inner.read(&mut buf[..n])?;
        self.left -= got as u64;
        Ok(got)
    }
}

/// Opens a regular file ([`open_regular`]) for streaming through a [`LimitedReader`] of
/// `max_bytes`; a declared size beyond it is refused at once.
pub fn open_limited(path: &Path, max_bytes: u64) -> std::io::Result<LimitedReader> {
    let f = open_regular(path)?;
    let len = f.metadata()?.len();
    if len > max_bytes {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("{len} bytes is more than the {max_bytes} this reader accepts"),
        ));
    }
    Ok(LimitedReader {
        inner: f,
        left: max_bytes,
        max_bytes,
    })
}

/// As [`read_limited`], as UTF-8 text.
pub fn read_text_limited(path: &Path, max_bytes: u64) -> std::io::Result<String> {
    String::from_utf8(read_limited(path, max_bytes)?)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "not UTF-8 text"))
}

/// The most values a time series of frames may hold, over all frames: 2^30 (8 GiB of values),
/// and fewer when the memory this process may use holds fewer ([`series_node_limit`]).
pub const MAX_SERIES_NODES: usize = 1 << 30;

/// Bytes of memory a loader holds per value at its peak: the file's own values (up to 8 bytes),
/// their float64 copy, and the float64 frames built from them (NetCDF through `netcdf-reader`;
/// the other formats hold less).
pub const BYTES_PER_LOADED_VALUE: u64 = 24;

/// The memory this process may still use, bytes, where the system says: the smallest of Linux's
/// `MemAvailable` (`/proc/meminfo`), the room left under a cgroup v2 limit (`memory.max` less
/// `memory.current`, as a Slurm job or a container sets) and the room left under an
/// address-space limit (`ulimit -v`, as HPC login nodes and `prlimit` set: the soft limit in
/// `/proc/self/limits` less the process's virtual size `VmSize` in `/proc/self/status`).
/// `None` where none is known. Read by hand: text files, no crate needed for them.
pub fn memory_budget_bytes() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        let line = t.lines().find(|l| l.starts_with("MemAvailable:"))?;
        let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        kib.checked_mul(1024)
    });
    let read_u64 = |f: &str| -> Option<u64> {
        std::fs::read_to_string(Path::new("/sys/fs/cgroup").join(f))
            .ok()?
            .trim()
            .parse()
            .ok()
    };
    let cgroup = read_u64("memory.max")
        .map(|max| max.saturating_sub(read_u64("memory.current").unwrap_or(0)));
    [meminfo, cgroup, address_space_room_bytes()]
        .into_iter()
        .flatten()
        .min()
}

/// The room left under this process's soft address-space limit (`RLIMIT_AS`, `ulimit -v`),
/// bytes: the limit less the virtual size already mapped. `None` when unlimited or unknown.
fn address_space_room_bytes() -> Option<u64> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let limit = parse_address_space_limit(&limits)?;
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    Some(limit.saturating_sub(parse_vm_size_bytes(&status)?))
}

/// The soft `Max address space` of a `/proc/PID/limits` text, bytes (`None` if `unlimited`).
pub(super) fn parse_address_space_limit(limits: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// `VmSize` of a `/proc/PID/status` text, bytes (the kernel writes it in kB = 1024 bytes).
pub(super) fn parse_vm_size_bytes(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmSize:"))?;
    let kib: u64 = line["VmSize:".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    kib.checked_mul(1024)
}

/// The most values (frames x nodes) a loader reads with `budget_bytes` of memory:
/// [`MAX_SERIES_NODES`], or fewer when the budget at [`BYTES_PER_LOADED_VALUE`] holds fewer.
pub fn series_node_limit(budget_bytes: Option<u64>) -> usize {
    let by_memory = budget_bytes.map_or(u64::MAX, |b| b / BYTES_PER_LOADED_VALUE);
    MAX_SERIES_NODES.min(usize::try_from(by_memory).unwrap_or(usize::MAX))
}

/// Checks a series' declared size (`frames` of `nx` x `ny` nodes, from a file's header) before
/// anything is allocated for it: each frame within [`crate::grid::MAX_NODES`], and frames x
/// nodes within [`series_node_limit`] of `budget_bytes`. The error names all three counts.
pub(crate) fn check_series_size(
    path: &Path,
    frames: usize,
    nx: usize,
    ny: usize,
    budget_bytes: Option<u64>,
) -> Result<(), LoadError> {
    let frame = nx.checked_mul(ny).filter(|n| *n <= crate::grid::MAX_NODES);
    if frame.is_none() {
        return Err(LoadError::grid(
            path,
            crate::grid::GridError::TooManyNodes { nx, ny },
        ));
    }
    let limit = series_node_limit(budget_bytes);
    let total = frame.and_then(|n| n.checked_mul(frames));
    if total.is_none_or(|n| n > limit) {
        let total = total.map_or_else(|| "more than 2^64".into(), |n| n.to_string());
        let why = match budget_bytes {
            Some(b) if limit < MAX_SERIES_NODES => format!(
                "the {:.1} GiB of memory this process may use holds {limit} at {BYTES_PER_LOADED_VALUE} bytes each while loading",
                b as f64 / f64::from(1u32 << 30)
            ),
            _ => format!("a series holds at most {MAX_SERIES_NODES}"),
        };
        return Err(LoadError::new(
            path,
            None,
            format!(
                "{frames} {} of {ny} x {nx} nodes = {total} values: too many to load ({why})",
                if frames == 1 { "frame" } else { "frames" }
            ),
        ));
    }
    Ok(())
}
