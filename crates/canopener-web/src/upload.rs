//! What the browser sends as a device description, judged before anything reads it: the size (the
//! cap, 16 MiB unless configured), the name (shown to the user, never used as a path: a name with a
//! folder, `..`, or control characters is refused, and only description extensions are taken) and
//! the content (a binary file is refused: CiA 306 and CiA 311 files are text).

/// The default cap on one upload.
pub const DEFAULT_CAP: usize = 16 * 1024 * 1024;

/// The extensions a device description may have.
pub const EXTENSIONS: [&str; 5] = ["eds", "dcf", "xdd", "xdc", "xpd"];

/// Why an upload is refused; the message is what the page shows.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Refusal {
    /// Larger than the cap.
    #[error(
        "{name}: {size} is more than this server accepts ({cap}); check a smaller file, or start the server with a larger --max-upload"
    )]
    TooLarge {
        /// The name as sent.
        name: String,
        /// The size, in words (`17.0 MiB`, or `more than 16 MiB` when the browser did not say).
        size: String,
        /// The cap, in words.
        cap: String,
    },
    /// The name says it is in a folder or climbs out of one.
    #[error(
        "{0:?}: a file name with a folder or `..` in it is refused; the server never uses a browser's file name as a path"
    )]
    PathInName(String),
    /// No name, or control characters in it.
    #[error("{0:?}: not a usable file name")]
    BadName(String),
    /// Not a device description by its name.
    #[error("{0}: not a device description; give an .eds, .dcf, .xdd, .xdc or .xpd file")]
    NotADescription(String),
    /// Binary content.
    #[error("{name}: binary content (a zero byte at offset {offset}); EDS, DCF and XDD files are text")]
    Binary {
        /// The name.
        name: String,
        /// Where the first zero byte is.
        offset: usize,
    },
    /// Nothing sent.
    #[error("{0}: the file is empty")]
    Empty(String),
}

/// `16 MiB`, `1.5 KiB`, `12 bytes`.
pub fn size_words(bytes: usize) -> String {
    const MIB: f64 = 1024.0 * 1024.0;
    let b = bytes as f64;
    if b >= MIB {
        let mib = b / MIB;
        if mib.fract() == 0.0 {
            format!("{mib:.0} MiB")
        } else {
            format!("{mib:.1} MiB")
        }
    } else if b >= 1024.0 {
        format!("{:.1} KiB", b / 1024.0)
    } else {
        format!("{bytes} bytes")
    }
}

/// Checks the name the browser gave: returns it when usable.
pub fn check_name(name: &str) -> Result<&str, Refusal> {
    if name.contains(['/', '\\']) || name.contains("..") {
        return Err(Refusal::PathInName(name.to_owned()));
    }
    if name.trim().is_empty() || name.chars().any(char::is_control) || name.len() > 255 {
        return Err(Refusal::BadName(name.to_owned()));
    }
    let extension = name.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase());
    if !extension.is_some_and(|e| EXTENSIONS.contains(&e.as_str())) {
        return Err(Refusal::NotADescription(name.to_owned()));
    }
    Ok(name)
}

/// Checks the size a browser announced (`Content-Length`) before reading the body.
pub fn check_announced(name: &str, announced: Option<usize>, cap: usize) -> Result<(), Refusal> {
    match announced {
        Some(size) if size > cap => Err(Refusal::TooLarge {
            name: name.to_owned(),
            size: size_words(size),
            cap: size_words(cap),
        }),
        _ => Ok(()),
    }
}

/// The refusal for a body that turned out longer than the cap while it was read.
pub fn too_large(name: &str, cap: usize) -> Refusal {
    Refusal::TooLarge {
        name: name.to_owned(),
        size: format!("more than {}", size_words(cap)),
        cap: size_words(cap),
    }
}

/// Checks the content: not empty, no zero byte (UTF-16 XML with its zero bytes is refused too: no
/// tool writes CiA 311 files so, and CiA 311 names UTF-8).
pub fn check_content(name: &str, bytes: &[u8]) -> Result<(), Refusal> {
    if bytes.is_empty() {
        return Err(Refusal::Empty(name.to_owned()));
    }
    if let Some(offset) = bytes.iter().position(|b| *b == 0) {
        return Err(Refusal::Binary {
            name: name.to_owned(),
            offset,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_with_folders_or_parents_are_refused_plain_names_pass() {
        assert_eq!(check_name("motor.eds"), Ok("motor.eds"));
        assert_eq!(check_name("Motor v1.2.XDD"), Ok("Motor v1.2.XDD"));
        for hostile in [
            "../motor.eds",
            "..\\motor.eds",
            "/etc/motor.eds",
            "a/b.eds",
            "x..eds",
        ] {
            assert_eq!(
                check_name(hostile),
                Err(Refusal::PathInName(hostile.to_owned())),
                "{hostile}"
            );
        }
        assert!(matches!(
            check_name("motor.exe"),
            Err(Refusal::NotADescription(_))
        ));
        assert!(matches!(check_name("mo\ntor.eds"), Err(Refusal::BadName(_))));
        assert!(matches!(check_name(""), Err(Refusal::BadName(_))));
        let message = check_name("../x.eds").unwrap_err().to_string();
        assert!(
            message.contains("never uses a browser's file name as a path"),
            "{message}"
        );
    }

    #[test]
    fn sizes_above_the_cap_are_refused_with_both_sizes_named() {
        assert_eq!(check_announced("a.eds", Some(DEFAULT_CAP), DEFAULT_CAP), Ok(()));
        let refusal = check_announced("a.eds", Some(17 * 1024 * 1024), DEFAULT_CAP).unwrap_err();
        assert_eq!(
            refusal.to_string(),
            "a.eds: 17 MiB is more than this server accepts (16 MiB); check a smaller file, or start the \
             server with a larger --max-upload"
        );
        assert!(
            too_large("a.eds", DEFAULT_CAP)
                .to_string()
                .contains("more than 16 MiB")
        );
        assert_eq!(size_words(1536), "1.5 KiB");
        assert_eq!(size_words(12), "12 bytes");
    }

    #[test]
    fn binary_and_empty_content_is_refused_text_in_any_encoding_passes() {
        assert_eq!(check_content("a.eds", b"[FileInfo]\r\n"), Ok(()));
        assert_eq!(
            check_content("a.eds", b"Vendor=M\xfcller\n"),
            Ok(()),
            "Windows-1252"
        );
        assert_eq!(
            check_content("a.eds", b"\x89PNG\r\n\x1a\n\0\0"),
            Err(Refusal::Binary {
                name: "a.eds".to_owned(),
                offset: 8
            })
        );
        assert!(matches!(check_content("a.eds", b""), Err(Refusal::Empty(_))));
    }
}
