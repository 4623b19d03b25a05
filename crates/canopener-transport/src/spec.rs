//! Bus spec strings: how every canopener command names the bus it talks to (`--bus SPEC`).
//!
//! The grammar, with examples:
//! - `virtual:NAME`, e.g. `virtual:demo`: an in-process bus with ideal timing;
//! - `virtual:NAME?bitrate=RATE`, e.g. `virtual:demo?bitrate=500k`: the same, bit-accurate in real time;
//! - `socketcand://HOST[:PORT]/BUS`, e.g. `socketcand://127.0.0.1:29536/can0` (port 29536 when left
//!   out; IPv6 hosts in brackets, `socketcand://[::1]/can0`);
//! - `socketcan:IFACE`, e.g. `socketcan:can0`: Linux SocketCAN;
//! - `udp-multicast://GROUP:PORT`, e.g. `udp-multicast://239.74.163.2:43113` (python-can's default,
//!   also used for a bare `udp-multicast`; IPv6 groups in brackets).
//!
//! `Display` writes the canonical form (explicit port, brackets around IPv6), which parses back to
//! the same value.

use std::ffi::OsString;
use std::fmt;
use std::net::{IpAddr, Ipv6Addr};
use std::str::FromStr;

use canopener_can::{Bitrate, BitrateError};

use crate::error::TransportError;
use crate::udp_multicast::{DEFAULT_GROUP, DEFAULT_PORT};

/// The TCP port socketcand listens on by default.
pub const DEFAULT_SOCKETCAND_PORT: u16 = 29536;
/// The environment variable that supplies the bus spec when no `--bus` argument is given.
pub const BUS_ENV_VAR: &str = "CANOPENER_BUS";
/// The longest bus name socketcand accepts (and therefore the longest virtual bus name).
pub const MAX_BUS_NAME_LEN: usize = 16;
/// The longest Linux network interface name (`IFNAMSIZ` minus the terminating NUL).
pub const MAX_INTERFACE_NAME_LEN: usize = 15;

const ACCEPTED_FORMS: &str = "accepted forms: virtual:NAME (e.g. virtual:demo), \
     virtual:NAME?bitrate=RATE (e.g. virtual:demo?bitrate=500k), \
     socketcand://HOST[:PORT]/BUS (e.g. socketcand://127.0.0.1:29536/can0, port 29536 by default), \
     socketcan:IFACE (e.g. socketcan:can0), \
     udp-multicast://GROUP:PORT (e.g. udp-multicast://239.74.163.2:43113)";

/// Which bus to open, parsed from a spec string.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum BusSpec {
    /// An in-process bus shared by every endpoint of this process that opens the same name.
    Virtual {
        /// The bus name: 1 to 16 characters of `A-Z a-z 0-9 _ . -`.
        name: String,
        /// `None` delivers instantly; `Some` makes every frame take its exact wire time.
        bitrate: Option<Bitrate>,
    },
    /// A bus behind a socketcand server, such as `canopener bus serve`.
    Socketcand {
        /// Host name or IP address (IPv6 without brackets).
        host: String,
        /// TCP port.
        port: u16,
        /// The server's bus name: 1 to 16 characters of `A-Z a-z 0-9 _ . -`.
        bus: String,
    },
    /// A Linux SocketCAN network interface.
    SocketCan {
        /// The interface name, at most 15 characters.
        interface: String,
    },
    /// A python-can-compatible UDP multicast bus.
    UdpMulticast {
        /// The multicast group.
        group: IpAddr,
        /// The UDP port.
        port: u16,
    },
}

/// A bus spec string that could not be parsed; the message lists every accepted form.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid bus spec {spec:?}: {problem}; {ACCEPTED_FORMS}")]
pub struct SpecError {
    /// The spec as given.
    pub spec: String,
    /// What is wrong with it.
    pub problem: SpecProblem,
}

/// What is wrong with a bus spec.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SpecProblem {
    /// The spec starts with none of the known schemes.
    #[error("it starts with none of virtual:, socketcand://, socketcan:, udp-multicast://")]
    UnknownScheme,
    /// A bus or interface name breaks the naming rules.
    #[error("{what} {name:?} {rule}")]
    BadName {
        /// `bus name` or `interface name`.
        what: &'static str,
        /// The name as given.
        name: String,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// The socketcand spec has no `/BUS` part.
    #[error("the socketcand bus name is missing; add it after a slash, e.g. /can0")]
    MissingBus,
    /// The host is empty or not a host name or IP address.
    #[error("host {0:?} is not a host name or IP address (IPv6 addresses go in brackets, e.g. [::1])")]
    BadHost(String),
    /// The port is not a number from 1 to 65535.
    #[error("port {0:?} is not a number from 1 to 65535")]
    BadPort(String),
    /// The multicast group is not an IP address.
    #[error("group {0:?} is not an IP address (IPv6 groups go in brackets)")]
    BadGroup(String),
    /// The group is an IP address outside the multicast ranges.
    #[error("{0} is not a multicast address (IPv4 224.0.0.0/4 or IPv6 ff00::/8)")]
    NotMulticast(IpAddr),
    /// A `?key=value` option the virtual bus does not know.
    #[error("unknown option {0:?}; the only option is bitrate, e.g. ?bitrate=500k")]
    UnknownOption(String),
    /// The bitrate option does not parse.
    #[error(transparent)]
    BadBitrate(BitrateError),
}

impl BusSpec {
    /// The spec for an ideal in-process bus named `name` (not validated; see [`FromStr`]).
    pub fn virtual_ideal(name: impl Into<String>) -> BusSpec {
        BusSpec::Virtual {
            name: name.into(),
            bitrate: None,
        }
    }
}

impl FromStr for BusSpec {
    type Err = SpecError;

    fn from_str(spec: &str) -> Result<BusSpec, SpecError> {
        parse(spec).map_err(|problem| SpecError {
            spec: spec.to_owned(),
            problem,
        })
    }
}

impl fmt::Display for BusSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BusSpec::Virtual { name, bitrate: None } => write!(f, "virtual:{name}"),
            BusSpec::Virtual {
                name,
                bitrate: Some(rate),
            } => write!(f, "virtual:{name}?bitrate={rate}"),
            BusSpec::Socketcand { host, port, bus } if host.contains(':') => {
                write!(f, "socketcand://[{host}]:{port}/{bus}")
            }
            BusSpec::Socketcand { host, port, bus } => write!(f, "socketcand://{host}:{port}/{bus}"),
            BusSpec::SocketCan { interface } => write!(f, "socketcan:{interface}"),
            BusSpec::UdpMulticast {
                group: IpAddr::V6(group),
                port,
            } => {
                write!(f, "udp-multicast://[{group}]:{port}")
            }
            BusSpec::UdpMulticast { group, port } => write!(f, "udp-multicast://{group}:{port}"),
        }
    }
}

/// The bus spec from `--bus` when given, else from `CANOPENER_BUS`; an error with examples when
/// neither names a bus.
pub fn spec_from_env_or(arg: Option<&str>) -> Result<BusSpec, TransportError> {
    spec_from(arg, std::env::var_os(BUS_ENV_VAR))
}

fn spec_from(arg: Option<&str>, env: Option<OsString>) -> Result<BusSpec, TransportError> {
    if let Some(arg) = arg {
        return Ok(arg.parse()?);
    }
    let env = env
        .filter(|value| !value.is_empty())
        .ok_or(TransportError::NoBusGiven)?;
    let env = env.into_string().map_err(|_| TransportError::EnvNotUnicode)?;
    env.parse().map_err(TransportError::EnvSpec)
}

fn parse(spec: &str) -> Result<BusSpec, SpecProblem> {
    if let Some(rest) = strip_scheme(spec, "socketcand://") {
        parse_socketcand(rest)
    } else if let Some(rest) = strip_scheme(spec, "udp-multicast://") {
        parse_udp_multicast(rest)
    } else if strip_scheme(spec, "udp-multicast").is_some_and(str::is_empty) {
        Ok(BusSpec::UdpMulticast {
            group: IpAddr::V4(DEFAULT_GROUP),
            port: DEFAULT_PORT,
        })
    } else if let Some(rest) = strip_scheme(spec, "virtual:") {
        parse_virtual(rest)
    } else if let Some(rest) = strip_scheme(spec, "socketcan:") {
        validate_interface(rest)?;
        Ok(BusSpec::SocketCan {
            interface: rest.to_owned(),
        })
    } else {
        Err(SpecProblem::UnknownScheme)
    }
}

/// `spec` without `scheme`, which matches ASCII case-insensitively.
fn strip_scheme<'a>(spec: &'a str, scheme: &str) -> Option<&'a str> {
    let head = spec.get(..scheme.len())?;
    head.eq_ignore_ascii_case(scheme).then(|| &spec[scheme.len()..])
}

fn parse_virtual(rest: &str) -> Result<BusSpec, SpecProblem> {
    let (name, query) = match rest.split_once('?') {
        Some((name, query)) => (name, Some(query)),
        None => (rest, None),
    };
    validate_bus_name(name)?;
    let mut bitrate = None;
    for option in query.into_iter().flat_map(|q| q.split('&')) {
        match option.split_once('=') {
            Some(("bitrate", value)) => bitrate = Some(value.parse().map_err(SpecProblem::BadBitrate)?),
            _ => return Err(SpecProblem::UnknownOption(option.to_owned())),
        }
    }
    Ok(BusSpec::Virtual {
        name: name.to_owned(),
        bitrate,
    })
}

fn parse_socketcand(rest: &str) -> Result<BusSpec, SpecProblem> {
    let (authority, bus) = rest.split_once('/').ok_or(SpecProblem::MissingBus)?;
    if bus.is_empty() {
        return Err(SpecProblem::MissingBus);
    }
    validate_bus_name(bus)?;
    let (host, port) = split_host_port(authority, SpecProblem::BadHost)?;
    if host.is_empty() || !(host.parse::<IpAddr>().is_ok() || is_host_name(host)) {
        return Err(SpecProblem::BadHost(host.to_owned()));
    }
    let port = port
        .map(parse_port)
        .transpose()?
        .unwrap_or(DEFAULT_SOCKETCAND_PORT);
    Ok(BusSpec::Socketcand {
        host: host.to_owned(),
        port,
        bus: bus.to_owned(),
    })
}

fn parse_udp_multicast(rest: &str) -> Result<BusSpec, SpecProblem> {
    let (group, port) = split_host_port(rest, SpecProblem::BadGroup)?;
    let group = if group.is_empty() {
        IpAddr::V4(DEFAULT_GROUP)
    } else {
        group
            .parse::<IpAddr>()
            .map_err(|_| SpecProblem::BadGroup(group.to_owned()))?
    };
    if !group.is_multicast() {
        return Err(SpecProblem::NotMulticast(group));
    }
    let port = port.map(parse_port).transpose()?.unwrap_or(DEFAULT_PORT);
    Ok(BusSpec::UdpMulticast { group, port })
}

/// Splits `HOST[:PORT]` or `[IPV6][:PORT]`; the host comes back without brackets.
fn split_host_port(
    authority: &str,
    bad_host: fn(String) -> SpecProblem,
) -> Result<(&str, Option<&str>), SpecProblem> {
    if let Some(bracketed) = authority.strip_prefix('[') {
        let (host, after) = bracketed
            .split_once(']')
            .ok_or_else(|| bad_host(authority.to_owned()))?;
        if host.parse::<Ipv6Addr>().is_err() {
            return Err(bad_host(host.to_owned()));
        }
        return match after {
            "" => Ok((host, None)),
            _ => after
                .strip_prefix(':')
                .map(|port| (host, Some(port)))
                .ok_or_else(|| bad_host(authority.to_owned())),
        };
    }
    match authority.split_once(':') {
        // A second colon means an IPv6 address without brackets: its last group would be taken
        // for a port.
        Some((_, port)) if port.contains(':') => Err(bad_host(authority.to_owned())),
        Some((host, port)) => Ok((host, Some(port))),
        None => Ok((authority, None)),
    }
}

fn parse_port(port: &str) -> Result<u16, SpecProblem> {
    let bad = || SpecProblem::BadPort(port.to_owned());
    if port.is_empty() || !port.bytes().all(|b| b.is_ascii_digit()) {
        return Err(bad());
    }
    match port.parse::<u16>() {
        Ok(0) | Err(_) => Err(bad()),
        Ok(port) => Ok(port),
    }
}

fn is_host_name(host: &str) -> bool {
    host.len() <= 253
        && host.split('.').all(|label| {
            !label.is_empty()
                && label.len() <= 63
                && label
                    .bytes()
                    .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_')
        })
}

pub(crate) fn validate_bus_name(name: &str) -> Result<(), SpecProblem> {
    let bad = |rule| SpecProblem::BadName {
        what: "bus name",
        name: name.to_owned(),
        rule,
    };
    if name.is_empty() {
        return Err(bad("is empty; name the bus, e.g. can0"));
    }
    if name.chars().count() > MAX_BUS_NAME_LEN {
        return Err(bad("is longer than 16 characters"));
    }
    if !name
        .bytes()
        .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'_' | b'.' | b'-'))
    {
        return Err(bad("may only contain letters, digits, _ . and -"));
    }
    Ok(())
}

fn validate_interface(name: &str) -> Result<(), SpecProblem> {
    let bad = |rule| SpecProblem::BadName {
        what: "interface name",
        name: name.to_owned(),
        rule,
    };
    if name.is_empty() {
        return Err(bad("is empty; name the interface, e.g. can0"));
    }
    if name.chars().count() > MAX_INTERFACE_NAME_LEN {
        return Err(bad("is longer than 15 characters, the Linux limit"));
    }
    // The kernel's dev_valid_name(): no '/', ':' or whitespace, and not "." or "..".
    if name == "."
        || name == ".."
        || !name
            .bytes()
            .all(|b| b.is_ascii_graphic() && b != b'/' && b != b':')
    {
        return Err(bad("may not contain /, : or spaces and may not be . or .."));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::net::Ipv4Addr;

    fn parse_ok(spec: &str) -> BusSpec {
        spec.parse().unwrap_or_else(|err| panic!("{spec}: {err}"))
    }

    fn problem(spec: &str) -> SpecProblem {
        spec.parse::<BusSpec>().expect_err(spec).problem
    }

    #[test]
    fn accepted_forms() {
        let cases = [
            ("virtual:demo", BusSpec::virtual_ideal("demo"), "virtual:demo"),
            (
                "virtual:bus_1.a-b?bitrate=500k",
                BusSpec::Virtual {
                    name: "bus_1.a-b".into(),
                    bitrate: Some(Bitrate::K500),
                },
                "virtual:bus_1.a-b?bitrate=500k",
            ),
            (
                "virtual:x?bitrate=1000000",
                BusSpec::Virtual {
                    name: "x".into(),
                    bitrate: Some(Bitrate::M1),
                },
                "virtual:x?bitrate=1M",
            ),
            (
                "socketcand://127.0.0.1:29536/can0",
                BusSpec::Socketcand {
                    host: "127.0.0.1".into(),
                    port: 29536,
                    bus: "can0".into(),
                },
                "socketcand://127.0.0.1:29536/can0",
            ),
            (
                "socketcand://hub.example-1.org/can1",
                BusSpec::Socketcand {
                    host: "hub.example-1.org".into(),
                    port: 29536,
                    bus: "can1".into(),
                },
                "socketcand://hub.example-1.org:29536/can1",
            ),
            (
                "socketcand://[::1]/can0",
                BusSpec::Socketcand {
                    host: "::1".into(),
                    port: 29536,
                    bus: "can0".into(),
                },
                "socketcand://[::1]:29536/can0",
            ),
            (
                "socketcand://[fe80::1]:4000/vcan",
                BusSpec::Socketcand {
                    host: "fe80::1".into(),
                    port: 4000,
                    bus: "vcan".into(),
                },
                "socketcand://[fe80::1]:4000/vcan",
            ),
            (
                "socketcan:can0",
                BusSpec::SocketCan {
                    interface: "can0".into(),
                },
                "socketcan:can0",
            ),
            (
                "SocketCAN:vcan0",
                BusSpec::SocketCan {
                    interface: "vcan0".into(),
                },
                "socketcan:vcan0",
            ),
            (
                "udp-multicast://239.74.163.2:43113",
                BusSpec::UdpMulticast {
                    group: IpAddr::V4(DEFAULT_GROUP),
                    port: 43113,
                },
                "udp-multicast://239.74.163.2:43113",
            ),
            (
                "udp-multicast://239.1.2.3",
                BusSpec::UdpMulticast {
                    group: IpAddr::V4(Ipv4Addr::new(239, 1, 2, 3)),
                    port: 43113,
                },
                "udp-multicast://239.1.2.3:43113",
            ),
            (
                "udp-multicast",
                BusSpec::UdpMulticast {
                    group: IpAddr::V4(DEFAULT_GROUP),
                    port: DEFAULT_PORT,
                },
                "udp-multicast://239.74.163.2:43113",
            ),
            (
                "udp-multicast://",
                BusSpec::UdpMulticast {
                    group: IpAddr::V4(DEFAULT_GROUP),
                    port: DEFAULT_PORT,
                },
                "udp-multicast://239.74.163.2:43113",
            ),
            (
                "udp-multicast://[ff15:7079:7468:6f6e:6465:6d6f:6d63:6173]:43113",
                BusSpec::UdpMulticast {
                    group: "ff15:7079:7468:6f6e:6465:6d6f:6d63:6173".parse().unwrap(),
                    port: 43113,
                },
                "udp-multicast://[ff15:7079:7468:6f6e:6465:6d6f:6d63:6173]:43113",
            ),
        ];
        for (text, expected, canonical) in cases {
            let spec = parse_ok(text);
            assert_eq!(spec, expected, "{text}");
            assert_eq!(spec.to_string(), canonical, "{text}");
            assert_eq!(parse_ok(canonical), expected, "{canonical}");
        }
    }

    #[test]
    fn rejected_forms_say_why() {
        assert_eq!(problem("can0"), SpecProblem::UnknownScheme);
        assert_eq!(problem(""), SpecProblem::UnknownScheme);
        assert_eq!(problem("tcp://127.0.0.1/can0"), SpecProblem::UnknownScheme);
        assert!(matches!(
            problem("virtual:"),
            SpecProblem::BadName { what: "bus name", .. }
        ));
        assert!(matches!(
            problem("virtual:abcdefghijklmnopq"),
            SpecProblem::BadName { .. }
        ));
        assert!(matches!(problem("virtual:a b"), SpecProblem::BadName { .. }));
        assert!(matches!(problem("virtual:bü"), SpecProblem::BadName { .. }));
        assert_eq!(
            problem("virtual:a?speed=5"),
            SpecProblem::UnknownOption("speed=5".into())
        );
        assert_eq!(
            problem("virtual:a?bitrate"),
            SpecProblem::UnknownOption("bitrate".into())
        );
        assert!(matches!(
            problem("virtual:a?bitrate=2M"),
            SpecProblem::BadBitrate(BitrateError::TooHigh(_))
        ));
        assert_eq!(problem("socketcand://127.0.0.1:29536"), SpecProblem::MissingBus);
        assert_eq!(problem("socketcand://127.0.0.1:29536/"), SpecProblem::MissingBus);
        assert!(matches!(
            problem("socketcand://h/can/0"),
            SpecProblem::BadName { .. }
        ));
        assert_eq!(
            problem("socketcand://:29536/can0"),
            SpecProblem::BadHost(String::new())
        );
        assert_eq!(
            problem("socketcand://::1:29536/can0"),
            SpecProblem::BadHost("::1:29536".into())
        );
        assert_eq!(
            problem("socketcand://[::1/can0"),
            SpecProblem::BadHost("[::1".into())
        );
        assert_eq!(
            problem("socketcand://[nope]:1/can0"),
            SpecProblem::BadHost("nope".into())
        );
        assert_eq!(
            problem("socketcand://[::1]x/can0"),
            SpecProblem::BadHost("[::1]x".into())
        );
        assert_eq!(
            problem("socketcand://bad host/can0"),
            SpecProblem::BadHost("bad host".into())
        );
        assert_eq!(
            problem("socketcand://a..b/can0"),
            SpecProblem::BadHost("a..b".into())
        );
        assert_eq!(problem("socketcand://h:0/can0"), SpecProblem::BadPort("0".into()));
        assert_eq!(
            problem("socketcand://h:65536/can0"),
            SpecProblem::BadPort("65536".into())
        );
        assert_eq!(
            problem("socketcand://h:+1/can0"),
            SpecProblem::BadPort("+1".into())
        );
        assert_eq!(
            problem("socketcand://h:/can0"),
            SpecProblem::BadPort(String::new())
        );
        assert!(matches!(
            problem("socketcan:"),
            SpecProblem::BadName {
                what: "interface name",
                ..
            }
        ));
        assert!(matches!(
            problem("socketcan:abcdefghijklmnop"),
            SpecProblem::BadName { .. }
        ));
        assert!(matches!(problem("socketcan:a/b"), SpecProblem::BadName { .. }));
        assert!(matches!(problem("socketcan:.."), SpecProblem::BadName { .. }));
        assert_eq!(
            problem("udp-multicast://10.0.0.1:43113"),
            SpecProblem::NotMulticast("10.0.0.1".parse().unwrap())
        );
        assert_eq!(
            problem("udp-multicast://239.1.1:43113"),
            SpecProblem::BadGroup("239.1.1".into())
        );
        assert_eq!(
            problem("udp-multicast://239.1.1.1:port"),
            SpecProblem::BadPort("port".into())
        );
        assert_eq!(problem("udp-multicastx"), SpecProblem::UnknownScheme);
    }

    #[test]
    fn every_error_lists_all_accepted_forms() {
        for bad in [
            "nonsense",
            "virtual:",
            "socketcand://h",
            "socketcan:",
            "udp-multicast://1.2.3.4:1",
        ] {
            let message = bad.parse::<BusSpec>().unwrap_err().to_string();
            assert!(
                message.starts_with(&format!("invalid bus spec {bad:?}: ")),
                "{message}"
            );
            for form in [
                "virtual:demo",
                "virtual:demo?bitrate=500k",
                "socketcand://127.0.0.1:29536/can0",
                "socketcan:can0",
                "udp-multicast://239.74.163.2:43113",
            ] {
                assert!(message.contains(form), "{message} lacks {form}");
            }
        }
    }

    #[test]
    fn argument_wins_over_environment() {
        let env = Some(OsString::from("virtual:from-env"));
        assert_eq!(
            spec_from(Some("virtual:from-arg"), env.clone()).unwrap(),
            BusSpec::virtual_ideal("from-arg")
        );
        assert_eq!(spec_from(None, env).unwrap(), BusSpec::virtual_ideal("from-env"));
    }

    #[test]
    fn missing_or_bad_environment_gives_examples() {
        for env in [None, Some(OsString::new())] {
            let err = spec_from(None, env).unwrap_err();
            assert!(matches!(err, TransportError::NoBusGiven), "{err:?}");
            let message = err.to_string();
            assert!(
                message.contains("--bus") && message.contains("CANOPENER_BUS"),
                "{message}"
            );
            assert!(message.contains("socketcand://127.0.0.1:29536/can0"), "{message}");
        }
        let err = spec_from(None, Some(OsString::from("bogus"))).unwrap_err();
        assert!(matches!(err, TransportError::EnvSpec(_)), "{err:?}");
        assert!(err.to_string().contains("CANOPENER_BUS"), "{err}");
        let err = spec_from(Some("bogus"), None).unwrap_err();
        assert!(matches!(err, TransportError::Spec(_)), "{err:?}");
    }

    #[cfg(unix)]
    #[test]
    fn non_unicode_environment_is_reported() {
        use std::os::unix::ffi::OsStringExt;
        let err = spec_from(None, Some(OsString::from_vec(vec![0x76, 0xff]))).unwrap_err();
        assert!(matches!(err, TransportError::EnvNotUnicode), "{err:?}");
    }

    fn bus_name() -> impl Strategy<Value = String> {
        "[A-Za-z0-9_.-]{1,16}"
    }

    fn any_spec() -> impl Strategy<Value = BusSpec> {
        let host = prop_oneof![
            "[a-z0-9]{1,10}(\\.[a-z0-9-]{1,10}){0,3}",
            any::<Ipv4Addr>().prop_map(|ip| ip.to_string()),
            any::<Ipv6Addr>().prop_map(|ip| ip.to_string()),
        ];
        let group = prop_oneof![
            (224u8..=239, any::<[u8; 3]>()).prop_map(|(a, [b, c, d])| IpAddr::V4(Ipv4Addr::new(a, b, c, d))),
            any::<[u16; 7]>()
                .prop_map(|s| IpAddr::V6(Ipv6Addr::new(0xff15, s[0], s[1], s[2], s[3], s[4], s[5], s[6]))),
        ];
        prop_oneof![
            (bus_name(), proptest::option::of(1u32..=1_000_000)).prop_map(|(name, bps)| BusSpec::Virtual {
                name,
                bitrate: bps.map(|bps| Bitrate::new(bps).unwrap())
            }),
            (host, 1u16.., bus_name()).prop_map(|(host, port, bus)| BusSpec::Socketcand { host, port, bus }),
            "[a-z0-9_.-]{1,15}"
                .prop_filter("not . or ..", |s| s != "." && s != "..")
                .prop_map(|interface| BusSpec::SocketCan { interface }),
            (group, 1u16..).prop_map(|(group, port)| BusSpec::UdpMulticast { group, port }),
        ]
    }

    proptest! {
        #[test]
        fn display_round_trips(spec in any_spec()) {
            prop_assert_eq!(spec.to_string().parse::<BusSpec>(), Ok(spec));
        }

        #[test]
        fn parsing_never_panics(text in "\\PC{0,60}") {
            let _ = text.parse::<BusSpec>();
        }
    }
}
