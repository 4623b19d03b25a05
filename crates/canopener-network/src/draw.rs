//! The SVG drawing of `canopener net draw`: devices at their X/Y (on the Background picture when the
//! file names one), else on a grid in cable order; networks coloured, gateways marked, cable names and
//! lengths on the cables, node-IDs and names on the devices.
//!
//! The automatic layout walks the cables breadth-first from the first device and fills a grid row by
//! row in a snake, so neighbours on a line stay neighbours on the page; a cell is wider than any label
//! it holds (long names are shortened with `…`, the full name is in the `<title>`), so labels of an
//! automatic layout never overlap, at 100 devices as at 3.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::fmt::Write as _;

use crate::model::{Topology, Vertex, VertexKind};

/// The colours of networks 1, 2, … (repeating), distinguishable for the common colour blindnesses
/// (Okabe–Ito).
const PALETTE: [&str; 7] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000",
];

/// The colour network `net` is drawn in.
pub fn network_colour(net: u32) -> &'static str {
    #[allow(clippy::indexing_slicing, reason = "an index modulo the palette's length")]
    PALETTE[(net.saturating_sub(1) as usize) % PALETTE.len()]
}

const CELL_W: f64 = 210.0;
const CELL_H: f64 = 110.0;
const BOX_W: f64 = 140.0;
const BOX_H: f64 = 44.0;
const MARGIN: f64 = 40.0;
/// The least distance between the centres of two positioned vertices after scaling: a box and a
/// cable label between neighbours.
const MIN_CENTRE_DISTANCE: f64 = 230.0;
/// Characters of a name that fit in a box at the font size used (about 6.5 px per character).
const NAME_CHARS: usize = 20;

/// A device or wiring element placed on the page (centre coordinates).
#[derive(Debug, Clone, PartialEq)]
pub struct Placed {
    /// The vertex's index in [`Topology::vertices`].
    pub vertex: usize,
    /// Centre, x.
    pub x: f64,
    /// Centre, y.
    pub y: f64,
}

/// Where each vertex goes: at its X/Y (or where yEd drew it) when every vertex has a position (scaled
/// up when the coordinates are small), else on the automatic grid.
pub fn layout(topology: &Topology) -> Vec<Placed> {
    let given = !topology.vertices.is_empty() && topology.vertices.iter().all(|v| v.position().is_some());
    if given {
        let xs = topology.vertices.iter().filter_map(|v| Some(v.position()?.0));
        let ys = topology.vertices.iter().filter_map(|v| Some(v.position()?.1));
        let (min_x, max_x) = xs.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
        let (min_y, max_y) = ys.fold((f64::MAX, f64::MIN), |(a, b), y| (a.min(y), b.max(y)));
        let span = (max_x - min_x).max(max_y - min_y);
        // Coordinates in metres or on a small grid: spread them so boxes do not cover each other, and
        // so that neighbours leave room for a cable label between them.
        let nearest = nearest_pair(topology);
        let scale = [
            if span > 0.0 && span < 600.0 {
                600.0 / span
            } else {
                1.0
            },
            if nearest > 0.0 {
                MIN_CENTRE_DISTANCE / nearest
            } else {
                1.0
            },
            1.0,
        ]
        .into_iter()
        .fold(0.0, f64::max);
        // On a background the picture's own coordinates are kept (the picture starts at 0,0).
        let (origin_x, origin_y) = if topology.background.is_some() && scale == 1.0 {
            (0.0, 0.0)
        } else {
            (min_x, min_y)
        };
        return topology
            .vertices
            .iter()
            .enumerate()
            .map(|(vertex, v)| Placed {
                vertex,
                x: MARGIN + BOX_W / 2.0 + (v.position().map_or(0.0, |p| p.0) - origin_x) * scale,
                y: MARGIN + BOX_H / 2.0 + (v.position().map_or(0.0, |p| p.1) - origin_y) * scale,
            })
            .collect();
    }
    let order = cable_order(topology);
    let columns = ((order.len() as f64 * 1.5).sqrt().ceil() as usize).max(1);
    order
        .into_iter()
        .enumerate()
        .map(|(i, vertex)| {
            let row = i / columns;
            let col = if row.is_multiple_of(2) {
                i % columns
            } else {
                columns - 1 - i % columns
            };
            Placed {
                vertex,
                x: MARGIN + CELL_W / 2.0 + col as f64 * CELL_W,
                y: MARGIN + CELL_H / 2.0 + row as f64 * CELL_H,
            }
        })
        .collect()
}

/// The distance between the two closest positioned vertices (0 when fewer than two).
fn nearest_pair(topology: &Topology) -> f64 {
    let points: Vec<(f64, f64)> = topology.vertices.iter().filter_map(Vertex::position).collect();
    let mut nearest = f64::MAX;
    let mut rest = points.as_slice();
    while let Some((a, others)) = rest.split_first() {
        rest = others;
        for b in others {
            // Positions on one row or column are apart by their larger offset, as boxes are laid out.
            let d = (a.0 - b.0).abs().max((a.1 - b.1).abs());
            if d > 0.0 {
                nearest = nearest.min(d);
            }
        }
    }
    if nearest == f64::MAX { 0.0 } else { nearest }
}

/// Vertices breadth-first along the cables, starting at the first vertex of each unvisited part.
fn cable_order(topology: &Topology) -> Vec<usize> {
    let mut adjacent: BTreeMap<usize, BTreeSet<usize>> = BTreeMap::new();
    for (a, b) in topology.cable_ends().into_iter().flatten() {
        adjacent.entry(a).or_default().insert(b);
        adjacent.entry(b).or_default().insert(a);
    }
    let mut seen = BTreeSet::new();
    let mut order = Vec::with_capacity(topology.vertices.len());
    for start in 0..topology.vertices.len() {
        if !seen.insert(start) {
            continue;
        }
        let mut queue = VecDeque::from([start]);
        while let Some(v) = queue.pop_front() {
            order.push(v);
            for &w in adjacent.get(&v).into_iter().flatten() {
                if seen.insert(w) {
                    queue.push_back(w);
                }
            }
        }
    }
    order
}

/// What a drawing shows besides the system: its pictures, and whether it carries live state badges.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DrawOptions {
    /// The address of the `Background` picture; `None` draws without one.
    pub background: Option<String>,
    /// The address of each vertex's `NodeFig` picture, by index in [`Topology::vertices`]; a vertex
    /// without one is drawn plain.
    pub figures: BTreeMap<usize, String>,
    /// A state badge per network attachment of every device (`<g class="state" data-device="NAME"
    /// data-network="N" data-state="unknown">`) and `data-suspect="false"` on every cable and device,
    /// for a live monitor to update (the web front end's page contract, `docs/web.md`).
    pub live: bool,
}

impl DrawOptions {
    /// The pictures as the file names them, which a browser resolves beside the SVG (`net draw`).
    pub fn as_named(topology: &Topology) -> DrawOptions {
        DrawOptions {
            background: topology.background.clone(),
            figures: topology
                .vertices
                .iter()
                .enumerate()
                .filter_map(|(i, v)| Some((i, v.fig.clone().filter(|f| !f.trim().is_empty())?)))
                .collect(),
            live: false,
        }
    }
}

/// The drawing as a standalone SVG document, its pictures named as the file names them.
pub fn svg(topology: &Topology) -> String {
    svg_with(topology, &DrawOptions::as_named(topology))
}

/// The drawing with `options`: the pictures at the addresses given (a front end that serves them),
/// and state badges for a live view.
pub fn svg_with(topology: &Topology, options: &DrawOptions) -> String {
    // The layout places positions in the vertex list, each once.
    let placed: Vec<(&Vertex, Placed)> = layout(topology)
        .into_iter()
        .filter_map(|p| Some((topology.vertices.get(p.vertex)?, p)))
        .collect();
    let at: BTreeMap<usize, (f64, f64)> = placed.iter().map(|(_, p)| (p.vertex, (p.x, p.y))).collect();
    let width = placed.iter().map(|(_, p)| p.x).fold(0.0, f64::max) + BOX_W / 2.0 + MARGIN;
    let height =
        placed.iter().map(|(_, p)| p.y).fold(0.0, f64::max) + BOX_H / 2.0 + MARGIN + legend_height(topology);
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(out, r#"<rect width="100%" height="100%" fill="white"/>"#);
    if let Some(background) = &options.background {
        let _ = writeln!(
            out,
            r#"<image class="background" href="{0}" xlink:href="{0}" x="0" y="0" width="{width:.0}" height="{height:.0}" preserveAspectRatio="xMinYMin meet" opacity="0.5"/>"#,
            escape(background)
        );
    }
    let mut occupied: Vec<Rect> = placed.iter().map(|(vertex, p)| footprint(vertex, p)).collect();
    let mut cable_labels = String::new();
    out.push_str("<g class=\"cables\">\n");
    for (cable, ends) in topology.cables.iter().zip(topology.cable_ends()) {
        let Some((a, b)) = ends else { continue };
        let (Some(&(x1, y1)), Some(&(x2, y2))) = (at.get(&a), at.get(&b)) else {
            continue;
        };
        let net = cable.net.unwrap_or(1);
        let dash = if cable
            .line_type
            .as_deref()
            .is_some_and(|t| t.eq_ignore_ascii_case("drop"))
        {
            r#" stroke-dasharray="6 3""#
        } else {
            ""
        };
        let suspect = if options.live {
            r#" data-suspect="false""#
        } else {
            ""
        };
        let _ = writeln!(
            out,
            r#"<line class="cable" data-cable="{0}" data-network="{net}"{suspect} x1="{x1:.1}" y1="{y1:.1}" x2="{x2:.1}" y2="{y2:.1}" stroke="{1}" stroke-width="3"{dash}><title>{0}</title></line>"#,
            escape(&cable.label()),
            network_colour(net),
        );
        let mut label = cable.name.clone().unwrap_or_default();
        if let Some(length) = cable.length {
            label = format!("{label} {length} m").trim().to_owned();
        }
        if label.is_empty() {
            continue;
        }
        // The first free spot along the cable; a label with no free spot stays in the tooltip.
        if let Some(spot) = free_spot(
            &occupied,
            (x1, y1),
            (x2, y2),
            &label,
            (width, height - legend_height(topology)),
        ) {
            occupied.push(spot);
            let _ = writeln!(
                cable_labels,
                r#"<text class="cable-label" x="{:.1}" y="{:.1}" text-anchor="middle" font-size="9" fill="{}" stroke="white" stroke-width="3" paint-order="stroke">{}</text>"#,
                (spot.0 + spot.2) / 2.0,
                spot.3 - 3.0,
                network_colour(net),
                escape(&label)
            );
        }
    }
    out.push_str("</g>\n<g class=\"devices\">\n");
    for (vertex, p) in &placed {
        let (x, y) = (p.x, p.y);
        let nets = vertex.networks();
        let colour = nets.iter().next().map_or("#555555", |&n| network_colour(n));
        let suspect = if options.live && vertex.is_device() {
            r#" data-suspect="false""#
        } else {
            ""
        };
        let _ = write!(
            out,
            r#"<g class="vertex {}" data-id="{}" data-name="{}"{suspect}><title>{}</title>"#,
            kind_class(vertex.kind()),
            escape(&vertex.id),
            escape(vertex.label()),
            escape(vertex.label())
        );
        let figure = options.figures.get(&p.vertex);
        match vertex.kind() {
            VertexKind::Passive | VertexKind::Active if figure.is_some() => {
                let _ = write!(
                    out,
                    r#"<image class="node-fig" href="{0}" xlink:href="{0}" x="{1:.1}" y="{2:.1}" width="24" height="24" preserveAspectRatio="xMidYMid meet"/>"#,
                    escape(figure.map_or("", String::as_str)),
                    x - 12.0,
                    y - 12.0
                );
            }
            VertexKind::Passive => {
                let _ = write!(out, r#"<circle cx="{x:.1}" cy="{y:.1}" r="5" fill="{colour}"/>"#);
            }
            VertexKind::Active => {
                let _ = write!(
                    out,
                    r#"<polygon points="{:.1},{y:.1} {x:.1},{:.1} {:.1},{y:.1} {x:.1},{:.1}" fill="white" stroke="{colour}" stroke-width="2"/>"#,
                    x - 14.0,
                    y - 14.0,
                    x + 14.0,
                    y + 14.0
                );
            }
            kind => {
                let (left, top) = (x - BOX_W / 2.0, y - BOX_H / 2.0);
                let _ = write!(
                    out,
                    r#"<rect class="box" x="{left:.1}" y="{top:.1}" width="{BOX_W}" height="{BOX_H}" rx="5" fill="white" stroke="{colour}" stroke-width="2"/>"#
                );
                if let Some(figure) = figure {
                    let _ = write!(
                        out,
                        r#"<image class="node-fig" href="{0}" xlink:href="{0}" x="{1:.1}" y="{2:.1}" width="{FIG}" height="{FIG}" preserveAspectRatio="xMidYMid meet"/>"#,
                        escape(figure),
                        left + 5.0,
                        y - FIG / 2.0
                    );
                }
                if kind == VertexKind::Gateway {
                    // A gateway: a second frame in the colour of its second network.
                    let second = nets.iter().nth(1).map_or(colour, |&n| network_colour(n));
                    let _ = write!(
                        out,
                        r#"<rect x="{:.1}" y="{:.1}" width="{}" height="{}" rx="7" fill="none" stroke="{second}" stroke-width="2"/>"#,
                        left - 4.0,
                        top - 4.0,
                        BOX_W + 8.0,
                        BOX_H + 8.0
                    );
                }
            }
        }
        let label_y = if vertex.is_device() { y - 4.0 } else { y + 22.0 };
        // A picture in the box takes the room of a few characters at its left.
        let (text_x, chars) = if figure.is_some() && vertex.is_device() {
            (x + (FIG + 5.0) / 2.0, NAME_CHARS - 6)
        } else {
            (x, NAME_CHARS)
        };
        let _ = write!(
            out,
            r#"<text class="name" x="{text_x:.1}" y="{label_y:.1}" text-anchor="middle" font-weight="bold">{}</text>"#,
            escape(&shorten(vertex.label(), chars))
        );
        if vertex.is_device() {
            let ids: Vec<String> = vertex
                .attachments
                .iter()
                .filter_map(|a| Some(format!("N{} #{}", a.net?, a.node_id?)))
                .collect();
            let _ = write!(
                out,
                r#"<text class="node-id" x="{text_x:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
                y + 12.0,
                escape(&shorten(&ids.join(" · "), chars + 4))
            );
            if options.live {
                state_badges(vertex, (x + BOX_W / 2.0, y - BOX_H / 2.0), &mut out);
            }
        }
        out.push_str("</g>\n");
    }
    out.push_str("</g>\n<g class=\"cable-labels\">\n");
    out.push_str(&cable_labels);
    out.push_str("</g>\n");
    legend(topology, height - legend_height(topology), &mut out);
    out.push_str("</svg>\n");
    out
}

/// The side of a `NodeFig` picture in a device's box.
const FIG: f64 = 34.0;

/// One badge per network the device is on, along the top edge of its box from the right corner.
fn state_badges(vertex: &Vertex, top_right: (f64, f64), out: &mut String) {
    let nets = vertex
        .attachments
        .iter()
        .filter_map(|a| a.net)
        .collect::<BTreeSet<u32>>();
    for (i, net) in nets.into_iter().enumerate() {
        let cx = top_right.0 - 10.0 - 18.0 * i as f64;
        let _ = write!(
            out,
            r#"<g class="state" data-device="{0}" data-network="{net}" data-state="unknown"><circle cx="{cx:.1}" cy="{1:.1}" r="7" stroke="{2}" stroke-width="2"/><title>{0} on network {net}: unknown</title></g>"#,
            escape(vertex.label()),
            top_right.1 + 2.0,
            network_colour(net),
        );
    }
}

/// A box on the page: left, top, right, bottom.
type Rect = (f64, f64, f64, f64);

/// What a vertex covers: its box (devices, couplers) or its dot and name below (junctions).
fn footprint(vertex: &Vertex, p: &Placed) -> Rect {
    match vertex.kind() {
        VertexKind::Passive | VertexKind::Active => {
            let half = (vertex.label().chars().count().min(NAME_CHARS) as f64 * CHAR_W_NAME / 2.0).max(15.0);
            (p.x - half, p.y - 15.0, p.x + half, p.y + 26.0)
        }
        _ => (
            p.x - BOX_W / 2.0 - 5.0,
            p.y - BOX_H / 2.0 - 5.0,
            p.x + BOX_W / 2.0 + 5.0,
            p.y + BOX_H / 2.0 + 5.0,
        ),
    }
}

/// Where a cable label of `text` fits along the cable from `a` to `b` without covering a vertex or
/// another label and inside the page: tried from the middle outwards, on and beside the line.
fn free_spot(occupied: &[Rect], a: (f64, f64), b: (f64, f64), text: &str, page: (f64, f64)) -> Option<Rect> {
    let w = text.chars().count() as f64 * CHAR_W_CABLE + 6.0;
    let h = 12.0;
    const ALONG: [f64; 9] = [0.5, 0.4, 0.6, 0.3, 0.7, 0.2, 0.8, 0.1, 0.9];
    // On the line, just beside it, and clear of the boxes of a row (a cable between neighbours).
    const BESIDE: [f64; 5] = [0.0, -9.0, 9.0, -(BOX_H / 2.0 + 13.0), BOX_H / 2.0 + 13.0];
    ALONG
        .iter()
        .flat_map(|t| BESIDE.iter().map(move |d| (*t, *d)))
        .find_map(|(t, d)| {
            let (cx, cy) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t + d);
            let rect = (cx - w / 2.0, cy - h / 2.0, cx + w / 2.0, cy + h / 2.0);
            let inside = rect.0 >= 0.0 && rect.1 >= 0.0 && rect.2 <= page.0 && rect.3 <= page.1;
            let free = occupied
                .iter()
                .all(|o| rect.2 <= o.0 || o.2 <= rect.0 || rect.3 <= o.1 || o.3 <= rect.1);
            (inside && free).then_some(rect)
        })
}

/// Generous widths of a character of a name (11 px bold) and a cable label (9 px), for placing.
const CHAR_W_NAME: f64 = 7.5;
const CHAR_W_CABLE: f64 = 5.8;

fn legend_height(topology: &Topology) -> f64 {
    20.0 * topology.network_numbers().len() as f64 + 10.0
}

fn legend(topology: &Topology, top: f64, out: &mut String) {
    out.push_str("<g class=\"legend\">\n");
    for (i, net) in topology.network_numbers().into_iter().enumerate() {
        let y = top + 20.0 * i as f64;
        let name = topology
            .network_name(net)
            .map(|n| format!(" {n}"))
            .unwrap_or_default();
        let _ = writeln!(
            out,
            r#"<line x1="{MARGIN}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="{}" stroke-width="3"/><text x="{:.1}" y="{:.1}">network {net}{}</text>"#,
            MARGIN + 30.0,
            network_colour(net),
            MARGIN + 36.0,
            y + 4.0,
            escape(&name)
        );
    }
    out.push_str("</g>\n");
}

fn kind_class(kind: VertexKind) -> &'static str {
    match kind {
        VertexKind::Device => "device",
        VertexKind::Manager => "device manager",
        VertexKind::Gateway => "device gateway",
        VertexKind::Passive => "passive",
        VertexKind::Active => "active",
    }
}

fn shorten(text: &str, chars: usize) -> String {
    if text.chars().count() <= chars {
        text.to_owned()
    } else {
        let mut out: String = text.chars().take(chars - 1).collect();
        out.push('…');
        out
    }
}

fn escape(text: &str) -> String {
    use canopener_eds::xml_text::{XmlPlace, XmlStyle};
    canopener_eds::xml_text::escape(text, XmlPlace::Attribute, XmlStyle::DECIMAL)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Attachment, Cable, Vertex};

    fn line(n: usize) -> Topology {
        let vertices = (1..=n)
            .map(|i| Vertex {
                id: format!("d{i}"),
                name: Some(format!("Device & {i}")),
                attachments: vec![Attachment {
                    slot: 1,
                    net: Some(1 + (i % 2) as u32),
                    node_id: Some(i as i64),
                    present: true,
                    ..Attachment::default()
                }],
                ..Vertex::default()
            })
            .collect();
        let cables = (1..n)
            .map(|i| Cable {
                source: format!("d{i}"),
                target: format!("d{}", i + 1),
                name: Some(format!("W{i}")),
                length: Some(2.5),
                ..Cable::default()
            })
            .collect();
        Topology {
            vertices,
            cables,
            ..Topology::default()
        }
    }

    #[test]
    fn an_automatic_layout_puts_every_vertex_in_its_own_cell() {
        let topology = line(100);
        let placed = layout(&topology);
        assert_eq!(placed.len(), 100);
        let cells: BTreeSet<(i64, i64)> = placed.iter().map(|p| (p.x as i64, p.y as i64)).collect();
        assert_eq!(cells.len(), 100);
        // Neighbours on the line stay neighbours on the page (the snake).
        for pair in placed.windows(2) {
            let d = (pair[0].x - pair[1].x).abs() + (pair[0].y - pair[1].y).abs();
            assert!(d <= CELL_H.max(CELL_W) + 0.1, "{pair:?}");
        }
    }

    #[test]
    fn the_svg_names_every_device_and_escapes_names_and_marks_networks() {
        let svg = svg(&line(3));
        assert!(svg.contains("Device &amp; 2"));
        assert!(svg.contains("N2 #1"));
        assert!(svg.contains("W1 2.5 m"));
        assert!(svg.contains(network_colour(2)));
        assert!(roxmltree::Document::parse(&svg).is_ok());
    }

    #[test]
    fn a_live_drawing_has_a_state_badge_per_network_and_names_cables_and_pictures() {
        let mut topology = line(3);
        topology.vertices[1].attachments.push(Attachment {
            slot: 2,
            net: Some(2),
            node_id: Some(9),
            present: true,
            ..Attachment::default()
        });
        topology.vertices[0].fig = Some("drive.png".to_owned());
        topology.background = Some("machine.png".to_owned());
        let plain = svg(&topology);
        assert!(plain.contains(r#"<image class="background" href="machine.png""#));
        assert!(plain.contains(r#"<image class="node-fig" href="drive.png""#));
        assert!(plain.contains(r#"data-cable="W1""#));
        assert!(
            !plain.contains("data-state"),
            "state badges are for live drawings only"
        );
        let options = DrawOptions {
            background: None,
            figures: BTreeMap::from([(2, "/fig/2".to_owned())]),
            live: true,
        };
        let live = svg_with(&topology, &options);
        assert!(!live.contains("machine.png") && !live.contains("drive.png"));
        assert!(live.contains(r#"href="/fig/2""#));
        let doc = roxmltree::Document::parse(&live).unwrap();
        let states: Vec<(String, String)> = doc
            .descendants()
            .filter(|n| n.attribute("class") == Some("state"))
            .map(|n| {
                (
                    n.attribute("data-device").unwrap().to_owned(),
                    n.attribute("data-network").unwrap().to_owned(),
                )
            })
            .collect();
        assert_eq!(
            states,
            [
                ("Device & 1".to_owned(), "2".to_owned()),
                ("Device & 2".to_owned(), "1".to_owned()),
                ("Device & 2".to_owned(), "2".to_owned()),
                ("Device & 3".to_owned(), "2".to_owned()),
            ]
        );
        let cables = doc
            .descendants()
            .filter(|n| n.attribute("data-cable").is_some())
            .count();
        assert_eq!(cables, 2);
        assert!(
            doc.descendants()
                .filter(|n| n.attribute("data-cable").is_some())
                .all(|n| n.attribute("data-suspect") == Some("false"))
        );
    }

    #[test]
    fn given_positions_are_kept_in_order() {
        let mut topology = line(2);
        topology.vertices[0].x = Some(1000.0);
        topology.vertices[0].y = Some(0.0);
        topology.vertices[1].x = Some(0.0);
        topology.vertices[1].y = Some(800.0);
        let placed = layout(&topology);
        assert!(placed[0].x > placed[1].x && placed[0].y < placed[1].y);
    }
}
