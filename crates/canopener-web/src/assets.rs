//! The pages' stylesheet and scripts, written by hand and compiled into the binary: no CDN, no build
//! step, the server works offline.

/// An asset by name: its content type and bytes.
pub fn get(name: &str) -> Option<(&'static str, &'static [u8])> {
    let bytes: &'static [u8] = match name {
        "style.css" => include_bytes!("../assets/style.css"),
        "common.js" => include_bytes!("../assets/common.js"),
        "monitor.js" => include_bytes!("../assets/monitor.js"),
        "check.js" => include_bytes!("../assets/check.js"),
        "test.js" => include_bytes!("../assets/test.js"),
        "report.css" => canopener_conformance::render::html::stylesheet().as_bytes(),
        _ => return None,
    };
    Some((content_type(name), bytes))
}

/// The content type of a file by its extension.
pub fn content_type(name: &str) -> &'static str {
    let extension = name
        .rsplit_once('.')
        .map(|(_, e)| e.to_ascii_lowercase())
        .unwrap_or_default();
    match extension.as_str() {
        "css" => "text/css; charset=utf-8",
        "js" => "text/javascript; charset=utf-8",
        "svg" => "image/svg+xml",
        "png" => "image/png",
        "jpg" | "jpeg" => "image/jpeg",
        "gif" => "image/gif",
        "bmp" => "image/bmp",
        "webp" => "image/webp",
        _ => "application/octet-stream",
    }
}
