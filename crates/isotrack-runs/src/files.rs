//! Which paths name one file.

use std::path::Path;

/// Whether two paths name the same existing file (same device and inode), not just the same
/// string: `a/../a/x` and a hard link count.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) if x == y => true,
        _ => {
            #[cfg(unix)]
            {
                use std::os::unix::fs::MetadataExt;
                match (std::fs::metadata(a), std::fs::metadata(b)) {
                    (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
                    _ => false,
                }
            }
            #[cfg(not(unix))]
            false
        }
    }
}
