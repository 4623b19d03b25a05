//! The live terminal view of `canopener net monitor`: per network, every device's NMT state, heartbeat
//! age and last EMCY, in the order of the drawing (top to bottom, left to right), and the latest
//! diagnosis of each network. Front-end code only: the state and the diagnoses come from
//! [`SystemMonitor`].

use std::collections::BTreeMap;

use canopener_can::Instant;
use canopener_link::link::Flow;
use canopener_network::Topology;
use canopener_network::monitor::{DeviceState, Event, SystemMonitor};
use ratatui::DefaultTerminal;
use ratatui::crossterm::event::{self, KeyCode, KeyModifiers};
use ratatui::layout::{Constraint, Layout};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, Borders, Paragraph, Row, Table, Wrap};

use crate::error::{CliError, CliResult};
use crate::net::monitor::line;

/// Slices of the watch (20 ms each) between redraws.
const REDRAW_EVERY: u32 = 10;

pub(crate) struct Tui {
    terminal: DefaultTerminal,
    title: String,
    /// Vertex index → its rank in the drawing's reading order.
    order: BTreeMap<usize, usize>,
    /// The latest diagnosis text per network.
    diagnoses: BTreeMap<u32, String>,
    slices: u32,
}

impl Tui {
    pub(crate) fn start(topology: &Topology, title: &str) -> CliResult<Tui> {
        let mut placed = canopener_network::draw::layout(topology);
        placed.sort_by(|a, b| a.y.total_cmp(&b.y).then(a.x.total_cmp(&b.x)));
        let order = placed
            .iter()
            .enumerate()
            .map(|(rank, p)| (p.vertex, rank))
            .collect();
        Ok(Tui {
            terminal: ratatui::try_init().map_err(|e| CliError::output("starting the terminal view", e))?,
            title: title.to_owned(),
            order,
            diagnoses: BTreeMap::new(),
            slices: 0,
        })
    }

    pub(crate) fn stop(self) {
        ratatui::restore();
    }

    /// Takes a slice's events; redraws now and then; `q`, Esc or Ctrl-C ends the view.
    pub(crate) fn update(
        &mut self,
        now: Instant,
        monitor: &SystemMonitor,
        events: Vec<Event>,
    ) -> CliResult<Flow<()>> {
        let changed = !events.is_empty();
        for event in &events {
            if let Event::Diagnosis { network, .. } = event {
                self.diagnoses
                    .insert(*network, line(event).trim_start().to_owned());
            }
        }
        while event::poll(std::time::Duration::ZERO)
            .map_err(|e| CliError::output("reading the terminal", e))?
        {
            if let event::Event::Key(key) =
                event::read().map_err(|e| CliError::output("reading the terminal", e))?
            {
                let ctrl_c = key.code == KeyCode::Char('c') && key.modifiers.contains(KeyModifiers::CONTROL);
                if ctrl_c || matches!(key.code, KeyCode::Char('q') | KeyCode::Esc) {
                    return Ok(Flow::Done(()));
                }
            }
        }
        self.slices += 1;
        if changed || self.slices >= REDRAW_EVERY {
            self.slices = 0;
            self.draw(now, monitor)?;
        }
        Ok(Flow::Continue)
    }

    fn draw(&mut self, now: Instant, monitor: &SystemMonitor) -> CliResult {
        let networks = monitor.networks();
        let title = self.title.clone();
        let order = &self.order;
        let diagnoses = &self.diagnoses;
        self.terminal
            .draw(|frame| {
                let mut constraints: Vec<Constraint> = networks.iter().map(|_| Constraint::Min(4)).collect();
                constraints.push(Constraint::Length(8));
                let areas = Layout::vertical(constraints).split(frame.area());
                for (i, &net) in networks.iter().enumerate() {
                    let mut devices: Vec<_> = monitor.devices().iter().filter(|d| d.network == net).collect();
                    devices.sort_by_key(|d| order.get(&d.vertex).copied().unwrap_or(usize::MAX));
                    let rows = devices.iter().map(|d| {
                        let state = if d.is_monitor {
                            "monitor".to_owned()
                        } else {
                            d.state.map_or("-", DeviceState::as_str).to_owned()
                        };
                        let colour = match d.state {
                            Some(DeviceState::Silent) => Color::Red,
                            Some(DeviceState::Operational) => Color::Green,
                            Some(DeviceState::Stopped) => Color::Yellow,
                            _ => Color::Reset,
                        };
                        let age = d
                            .last_heard
                            .map(|at| format!("{:.1} s", now.saturating_duration_since(at).as_secs_f64()))
                            .unwrap_or_else(|| "-".to_owned());
                        let emcy = d
                            .last_emcy
                            .map(|e| format!("{:04X}h reg {:02X}h", e.code, e.register))
                            .unwrap_or_else(|| "-".to_owned());
                        Row::new(vec![d.name.clone(), d.node_id.to_string(), state, age, emcy])
                            .style(Style::default().fg(colour))
                    });
                    let table = Table::new(
                        rows,
                        [
                            Constraint::Percentage(35),
                            Constraint::Length(8),
                            Constraint::Length(16),
                            Constraint::Length(10),
                            Constraint::Min(16),
                        ],
                    )
                    .header(
                        Row::new(["device", "node-ID", "state", "heard", "last EMCY"])
                            .style(Style::default().add_modifier(Modifier::BOLD)),
                    )
                    .block(
                        Block::default()
                            .borders(Borders::ALL)
                            .title(format!(" {title}: network {net} ")),
                    );
                    frame.render_widget(table, areas[i]);
                }
                let text: Vec<Line<'_>> = if diagnoses.is_empty() {
                    vec![Line::from("every device is heard   (q quits)")]
                } else {
                    diagnoses
                        .values()
                        .flat_map(|d| d.lines().map(|l| Line::from(l.to_owned())))
                        .collect()
                };
                let diagnosis = Paragraph::new(text)
                    .wrap(Wrap { trim: false })
                    .block(Block::default().borders(Borders::ALL).title(" diagnosis "));
                frame.render_widget(diagnosis, areas[networks.len()]);
            })
            .map_err(|e| CliError::output("drawing the terminal view", e))?;
        Ok(())
    }
}
