//! `fmuResourceLocation` (a `file` URI) to a local path.

use std::path::PathBuf;

/// The local path of a `file` URI as importers pass `fmuResourceLocation`:
/// `file:///abs/path`, `file:/abs/path` and `file://localhost/abs/path`,
/// percent-encoded (`%20` ...), with or without a trailing slash. The scheme
/// is case-insensitive; a remote host, a relative path, an invalid `%`
/// escape or an embedded NUL are refused with a message.
pub fn file_uri_to_path(uri: &str) -> Result<PathBuf, String> {
    let rest = match uri.get(..5) {
        Some(scheme) if scheme.eq_ignore_ascii_case("file:") => &uri[5..],
        _ => return Err(format!("{uri:?} is not a file: URI")),
    };
    let path = if let Some(after) = rest.strip_prefix("//") {
        // file://host/path: the authority ends at the next '/'.
        let slash = after.find('/').unwrap_or(after.len());
        let host = &after[..slash];
        if !(host.is_empty() || host.eq_ignore_ascii_case("localhost")) {
            return Err(format!("{uri:?} names the remote host {host:?}"));
        }
        &after[slash..]
    } else {
        rest
    };
    if !path.starts_with('/') {
        return Err(format!("{uri:?} does not hold an absolute path"));
    }
    // A query or fragment is not part of a resources folder URI.
    let path = path.split(['?', '#']).next().unwrap_or(path);
    let bytes = percent_decode(path).map_err(|e| format!("{uri:?}: {e}"))?;
    if bytes.contains(&0) {
        return Err(format!("{uri:?} holds a NUL byte"));
    }
    bytes_to_path(bytes).map_err(|e| format!("{uri:?}: {e}"))
}

fn percent_decode(s: &str) -> Result<Vec<u8>, String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = b
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("invalid percent escape at byte {i}"))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    Ok(out)
}

#[cfg(unix)]
fn bytes_to_path(bytes: Vec<u8>) -> Result<PathBuf, String> {
    use std::os::unix::ffi::OsStringExt;
    Ok(PathBuf::from(std::ffi::OsString::from_vec(bytes)))
}

#[cfg(not(unix))]
fn bytes_to_path(bytes: Vec<u8>) -> Result<PathBuf, String> {
    String::from_utf8(bytes)
        .map(PathBuf::from)
        .map_err(|_| "the path is not UTF-8".to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepted_forms() {
        let p = |s: &str| file_uri_to_path(s).unwrap();
        assert_eq!(
            p("file:///tmp/x/resources"),
            PathBuf::from("/tmp/x/resources")
        );
        assert_eq!(
            p("file:///tmp/x/resources/"),
            PathBuf::from("/tmp/x/resources/")
        );
        assert_eq!(
            p("file:/tmp/x/resources"),
            PathBuf::from("/tmp/x/resources")
        );
        assert_eq!(p("file://localhost/tmp/x"), PathBuf::from("/tmp/x"));
        assert_eq!(p("FILE://LocalHost/tmp/x"), PathBuf::from("/tmp/x"));
        assert_eq!(p("file:///tmp/a%20b/%C3%A9"), PathBuf::from("/tmp/a b/é"));
        assert_eq!(p("file:///tmp/100%25"), PathBuf::from("/tmp/100%"));
    }

    #[test]
    fn refused_forms() {
        for bad in [
            "/tmp/x",
            "http://x/y",
            "file://server/share",
            "file:relative/path",
            "file:///tmp/%zz",
            "file:///tmp/%2",
            "file:///tmp/%00",
            "",
        ] {
            assert!(file_uri_to_path(bad).is_err(), "{bad:?} accepted");
        }
    }
}
