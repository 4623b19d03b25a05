//! The pass criteria of the CiA 313 performance tests, read from a TOML file (`--criteria FILE`).
//!
//! CiA 301 sets no performance figures and CiA 313 says how to measure, not what is good enough: the
//! limits are the device maker's or the integrator's. Two have documented defaults, the thesis's
//! (`seeds/001`, §4.2.2) heartbeat deviation of ±5 % and the same ±5 % for a TPDO's event-timer
//! cycle; every response-time limit is unset unless the file sets it, and an unset limit makes the
//! test report its measurement with the verdict `pass` ("measured, no criterion").
//!
//! ```toml
//! [heartbeat]
//! deviation_percent = 5.0      # each period within 100 ms ±5 %
//! [pdo]
//! event_timer_deviation_percent = 5.0
//! sync_response_max_ms = 1.0   # SYNC sent → TPDO received
//! rtr_response_max_ms = 1.0    # remote frame sent → TPDO received
//! [sdo]
//! read_max_ms = 2.0            # request sent → response received, every repetition
//! write_max_ms = 2.0
//! [boot_up]
//! max_ms = 500.0               # NMT reset node sent → boot-up received
//! [lss]
//! response_max_ms = 5.0        # every confirmed LSS service
//! ```

use serde::Deserialize;

/// The criteria a run judges its measurements by (see the [module docs](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct Criteria {
    /// Where they come from: `None` for the defaults, else the file as the user named it.
    pub source: Option<String>,
    /// The keys the file set (`sdo.read_max_ms`); every other criterion is its default.
    pub set: Vec<&'static str>,
    /// The largest deviation of a heartbeat period from 1017h, in percent.
    pub heartbeat_deviation_percent: f64,
    /// The largest deviation of an event-driven TPDO's period from its event timer, in percent.
    pub event_timer_deviation_percent: f64,
    /// The longest SYNC → synchronous TPDO time, in ms.
    pub sync_response_max_ms: Option<f64>,
    /// The longest remote frame → TPDO time, in ms.
    pub rtr_response_max_ms: Option<f64>,
    /// The longest SDO upload request → response time, in ms.
    pub sdo_read_max_ms: Option<f64>,
    /// The longest SDO download request → response time, in ms.
    pub sdo_write_max_ms: Option<f64>,
    /// The longest NMT reset node → boot-up time, in ms.
    pub boot_up_max_ms: Option<f64>,
    /// The longest LSS request → answer time, in ms.
    pub lss_response_max_ms: Option<f64>,
}

/// The thesis's heartbeat deviation (`seeds/001`, §4.2.2: 95 ms ≤ period ≤ 105 ms at 100 ms).
pub const DEFAULT_DEVIATION_PERCENT: f64 = 5.0;

impl Default for Criteria {
    fn default() -> Criteria {
        Criteria::DEFAULT
    }
}

/// A criteria file that cannot be used: where and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}:{line}:{column}: {message}; see `docs/conformance.md` (criteria file) for the keys")]
pub struct CriteriaError {
    /// The file as the user named it.
    pub file: String,
    /// The line, from 1.
    pub line: usize,
    /// The column, from 1.
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

impl Criteria {
    /// The documented defaults: ±5 % for heartbeat and event timer, no response-time limits.
    pub const DEFAULT: Criteria = Criteria {
        source: None,
        set: Vec::new(),
        heartbeat_deviation_percent: DEFAULT_DEVIATION_PERCENT,
        event_timer_deviation_percent: DEFAULT_DEVIATION_PERCENT,
        sync_response_max_ms: None,
        rtr_response_max_ms: None,
        sdo_read_max_ms: None,
        sdo_write_max_ms: None,
        boot_up_max_ms: None,
        lss_response_max_ms: None,
    };

    /// Reads the criteria file `text` named `file`; keys it does not set keep their defaults.
    pub fn parse(text: &str, file: &str) -> Result<Criteria, CriteriaError> {
        let at = |span: Option<std::ops::Range<usize>>, message: String| {
            let (line, column) = line_column(text, span.map_or(0, |s| s.start));
            CriteriaError {
                file: file.to_owned(),
                line,
                column,
                message,
            }
        };
        let raw: File = toml::from_str(text).map_err(|err| at(err.span(), err.message().to_owned()))?;
        let mut criteria = Criteria {
            source: Some(file.to_owned()),
            ..Criteria::DEFAULT
        };
        let heartbeat = raw.heartbeat.unwrap_or_default();
        let pdo = raw.pdo.unwrap_or_default();
        let sdo = raw.sdo.unwrap_or_default();
        let mut set = Vec::new();
        let fields: [(&'static str, Option<Spanned>, Slot<'_>); 8] = [
            (
                "heartbeat.deviation_percent",
                heartbeat.deviation_percent,
                Slot::Percent(&mut criteria.heartbeat_deviation_percent),
            ),
            (
                "pdo.event_timer_deviation_percent",
                pdo.event_timer_deviation_percent,
                Slot::Percent(&mut criteria.event_timer_deviation_percent),
            ),
            (
                "pdo.sync_response_max_ms",
                pdo.sync_response_max_ms,
                Slot::Limit(&mut criteria.sync_response_max_ms),
            ),
            (
                "pdo.rtr_response_max_ms",
                pdo.rtr_response_max_ms,
                Slot::Limit(&mut criteria.rtr_response_max_ms),
            ),
            (
                "sdo.read_max_ms",
                sdo.read_max_ms,
                Slot::Limit(&mut criteria.sdo_read_max_ms),
            ),
            (
                "sdo.write_max_ms",
                sdo.write_max_ms,
                Slot::Limit(&mut criteria.sdo_write_max_ms),
            ),
            (
                "boot_up.max_ms",
                raw.boot_up.unwrap_or_default().max_ms,
                Slot::Limit(&mut criteria.boot_up_max_ms),
            ),
            (
                "lss.response_max_ms",
                raw.lss.unwrap_or_default().response_max_ms,
                Slot::Limit(&mut criteria.lss_response_max_ms),
            ),
        ];
        for (key, value, slot) in fields {
            let Some(value) = value else { continue };
            let number = value.get_ref().0;
            let span = Some(value.span());
            match slot {
                Slot::Percent(target) if number.is_finite() && number > 0.0 && number < 100.0 => {
                    *target = number;
                    set.push(key);
                }
                Slot::Percent(_) => {
                    return Err(at(
                        span,
                        format!("{key} = {number}: give a percentage above 0 and below 100, e.g. 5.0"),
                    ));
                }
                Slot::Limit(target) if number.is_finite() && number > 0.0 => {
                    *target = Some(number);
                    set.push(key);
                }
                Slot::Limit(_) => {
                    return Err(at(
                        span,
                        format!("{key} = {number}: give a time in ms above 0, e.g. 2.5"),
                    ));
                }
            }
        }
        criteria.set = set;
        Ok(criteria)
    }

    /// `sdo.read_max_ms from limits.toml` or `heartbeat.deviation_percent (documented default)`: who
    /// set the criterion `key`.
    pub fn origin(&self, key: &str) -> String {
        match &self.source {
            Some(file) if self.set.contains(&key) => format!("{key} from {file}"),
            _ => format!("{key} (documented default)"),
        }
    }
}

enum Slot<'a> {
    Percent(&'a mut f64),
    Limit(&'a mut Option<f64>),
}

/// A number in the file with where it is, for messages naming file:line.
type Spanned = toml::Spanned<Number>;

/// An integer or a float: `5` and `5.0` both mean five.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Number(f64);

impl<'de> Deserialize<'de> for Number {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Number, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Either {
            Int(i64),
            Float(f64),
        }
        match Either::deserialize(deserializer) {
            Ok(Either::Int(i)) => Ok(Number(i as f64)),
            Ok(Either::Float(f)) => Ok(Number(f)),
            Err(_) => Err(serde::de::Error::custom("expected a number")),
        }
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    heartbeat: Option<HeartbeatSection>,
    pdo: Option<PdoSection>,
    sdo: Option<SdoSection>,
    boot_up: Option<BootUpSection>,
    lss: Option<LssSection>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct HeartbeatSection {
    deviation_percent: Option<Spanned>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct PdoSection {
    event_timer_deviation_percent: Option<Spanned>,
    sync_response_max_ms: Option<Spanned>,
    rtr_response_max_ms: Option<Spanned>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct SdoSection {
    read_max_ms: Option<Spanned>,
    write_max_ms: Option<Spanned>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct BootUpSection {
    max_ms: Option<Spanned>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct LssSection {
    response_max_ms: Option<Spanned>,
}

/// The 1-based line and column of byte `offset` of `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = text.get(..offset.min(text.len())).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_file_keeps_the_documented_defaults() {
        let criteria = Criteria::parse("", "c.toml").unwrap();
        assert_eq!(criteria.heartbeat_deviation_percent, 5.0);
        assert_eq!(criteria.event_timer_deviation_percent, 5.0);
        assert_eq!(criteria.sdo_read_max_ms, None);
        assert_eq!(criteria.source.as_deref(), Some("c.toml"));
        assert_eq!(
            criteria.origin("heartbeat.deviation_percent"),
            "heartbeat.deviation_percent (documented default)"
        );
    }

    #[test]
    fn every_key_is_read_integers_too() {
        let text = "[heartbeat]\ndeviation_percent = 2\n[pdo]\nevent_timer_deviation_percent = 1.5\n\
                    sync_response_max_ms = 0.5\nrtr_response_max_ms = 0.6\n[sdo]\nread_max_ms = 1\n\
                    write_max_ms = 1.25\n[boot_up]\nmax_ms = 300\n[lss]\nresponse_max_ms = 4\n";
        let c = Criteria::parse(text, "c.toml").unwrap();
        assert_eq!(
            (c.heartbeat_deviation_percent, c.event_timer_deviation_percent),
            (2.0, 1.5)
        );
        assert_eq!(
            [
                c.sync_response_max_ms,
                c.rtr_response_max_ms,
                c.sdo_read_max_ms,
                c.sdo_write_max_ms,
                c.boot_up_max_ms,
                c.lss_response_max_ms
            ],
            [
                Some(0.5),
                Some(0.6),
                Some(1.0),
                Some(1.25),
                Some(300.0),
                Some(4.0)
            ]
        );
    }

    #[test]
    fn mistakes_name_file_line_and_column() {
        let typo = Criteria::parse("[sdo]\nread_max = 1\n", "c.toml").unwrap_err();
        assert_eq!((typo.line, typo.column), (2, 1), "{typo}");
        assert!(typo.to_string().starts_with("c.toml:2:1: "), "{typo}");
        assert!(typo.message.contains("read_max"), "{typo}");
        let negative = Criteria::parse("[heartbeat]\n\ndeviation_percent = -3\n", "c.toml").unwrap_err();
        assert_eq!(negative.line, 3, "{negative}");
        assert!(negative.message.contains("above 0"), "{negative}");
        let text = Criteria::parse("[lss]\nresponse_max_ms = \"fast\"\n", "c.toml").unwrap_err();
        assert_eq!(text.line, 2, "{text}");
        let broken = Criteria::parse("[sdo\n", "c.toml").unwrap_err();
        assert_eq!(broken.line, 1, "{broken}");
    }

    proptest::proptest! {
        #[test]
        fn any_text_is_read_or_refused_with_a_position_inside_it(text in "\\PC{0,200}") {
            if let Err(err) = Criteria::parse(&text, "c.toml") {
                proptest::prop_assert!(err.line >= 1 && err.line <= text.lines().count().max(1) + 1);
                proptest::prop_assert!(err.column >= 1);
            }
        }
    }
}
