//! `canopener net draw` rendered by headless Chromium (Debian's `chromium` package): every device's
//! name is on the page inside the drawing, and no two labels overlap in the automatic layout of 100
//! devices. Screenshots of the two-network drawings are left in the target directory for people.

use std::path::{Path, PathBuf};

use canopener_testkit::browser::{chromium, run as chromium_run};

use serde_json::Value;

use super::{run, stderr, stdout, temp_dir};

fn test_data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../canopener-network/test_data")
        .join(name)
}

/// Measures the drawing in the browser: every label's box, and the device titles.
const MEASURE: &str = r#"<script>
const svg = document.querySelector('svg');
const view = svg.viewBox.baseVal;
const labels = [...svg.querySelectorAll('text.name, text.node-id, text.cable-label')].map(t => {
  const b = t.getBBox();
  return {cls: t.getAttribute('class'), text: t.textContent, x: b.x, y: b.y, w: b.width, h: b.height,
          vertex: t.closest('g.vertex') ? t.closest('g.vertex').dataset.id : null};
});
const overlaps = [];
for (let i = 0; i < labels.length; i++) for (let j = i + 1; j < labels.length; j++) {
  const a = labels[i], b = labels[j];
  if (a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h) overlaps.push([a.text, b.text]);
}
const outside = labels.filter(l => l.x < 0 || l.y < 0 || l.x + l.w > view.width || l.y + l.h > view.height)
  .map(l => l.text);
const devices = [...svg.querySelectorAll('g.vertex.device')].map(g => ({
  title: g.querySelector('title').textContent,
  name: g.querySelector('text.name').textContent}));
const pre = document.createElement('pre');
pre.id = 'result';
pre.textContent = JSON.stringify({labels: labels.length, cables: labels.filter(l => l.cls === 'cable-label').length,
  overlaps, outside, devices});
document.body.appendChild(pre);
</script>"#;

fn measure(browser: &Path, dir: &Path, svg: &str) -> Value {
    let page = dir.join("page.html");
    std::fs::write(
        &page,
        // Without a declared charset Chromium guesses from the machine's locale, and the ellipsis of
        // a shortened name comes back as Latin-1 mojibake on some machines.
        format!(
            "<!doctype html><html><head><meta charset=\"utf-8\"></head><body>{svg}{MEASURE}</body></html>"
        ),
    )
    .expect("page");
    let dom = chromium_run(
        browser,
        &dir.join("profile"),
        &format!("file://{}", page.display()),
        &["--dump-dom"],
    );
    let start = dom.find("<pre id=\"result\">").expect("the script ran") + "<pre id=\"result\">".len();
    let text = &dom[start..start + dom[start..].find("</pre>").expect("end")];
    serde_json::from_str(
        &text
            .replace("&amp;", "&")
            .replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&quot;", "\""),
    )
    .expect("json")
}

fn draw(name: &str) -> String {
    let output = run(&["net", "draw", test_data(name).to_str().expect("utf-8")]);
    assert!(output.status.success(), "{}", stderr(&output));
    stdout(&output)
}

#[test]
fn a_hundred_devices_are_all_named_inside_the_drawing_without_overlapping_labels() {
    let Some(browser) = chromium() else { return };
    let dir = temp_dir("net-browser-100");
    let result = measure(browser, &dir, &draw("hundred.graphml"));
    let devices = result["devices"].as_array().expect("devices");
    assert_eq!(devices.len(), 100, "{result}");
    for device in devices {
        let (title, name) = (
            device["title"].as_str().unwrap_or(""),
            device["name"].as_str().unwrap_or(""),
        );
        // A long name is shortened with an ellipsis on the page; the full name is the tooltip.
        assert!(
            name == title || (name.ends_with('…') && title.starts_with(name.trim_end_matches('…'))),
            "{device}"
        );
    }
    assert_eq!(
        result["overlaps"],
        serde_json::json!([]),
        "labels overlap: {}",
        result["overlaps"]
    );
    assert_eq!(
        result["outside"],
        serde_json::json!([]),
        "labels outside the drawing: {}",
        result["outside"]
    );
    // A cable label without a free spot would only be the cable's tooltip: all 111 are on the page.
    assert_eq!(result["cables"], 111, "{}", result["cables"]);
}

#[test]
fn two_network_systems_render_with_every_device_and_leave_screenshots() {
    let Some(browser) = chromium() else { return };
    let dir = temp_dir("net-browser-two");
    for (name, devices) in [("gateway.graphml", 6), ("paper/Nodelist.graphml", 4)] {
        let svg = draw(name);
        let result = measure(browser, &dir, &svg);
        assert_eq!(
            result["devices"].as_array().map(Vec::len),
            Some(devices),
            "{name}: {result}"
        );
        assert_eq!(result["outside"], serde_json::json!([]), "{name}: {result}");
        // For people: net-<name>.png in cargo's scratch directory for integration tests (it exists
        // wherever CARGO_TARGET_DIR points). The paper's background is looked up beside the SVG.
        let svg_path = test_data(name).with_extension("svg.tmp.svg");
        let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
            "net-{}.png",
            name.replace('/', "-").replace(".graphml", "")
        ));
        std::fs::write(&svg_path, &svg).expect("svg");
        chromium_run(
            browser,
            &dir.join("profile"),
            &format!("file://{}", svg_path.display()),
            &[
                &format!("--screenshot={}", out.display()),
                "--window-size=1500,400",
            ],
        );
        let _ = std::fs::remove_file(&svg_path);
        assert!(out.exists(), "{}", out.display());
    }
}
