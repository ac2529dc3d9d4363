//! The `vrpn_Tracker_DTrack` line: its fields, its parser, what it serves and how it is built.

use std::net::{Ipv4Addr, SocketAddr, ToSocketAddrs};

use super::report::FixedNumbering;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::error::Error;

/// The port DTRACK controllers listen on for the stateful-firewall message.
pub const FIREWALL_PORT: u16 = 50107;

/// Where the frames come from (the second field).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Source {
    /// `PORT`: frames sent to this port.
    Port(u16),
    /// `GROUP:PORT`: frames sent to a multicast group (224.0.0.0/4).
    Multicast(Ipv4Addr, u16),
    /// `HOST:PORT:fw`: frames sent to this port by the controller at `HOST`, which is sent
    /// a message from the port first so that a stateful firewall lets its frames in.
    Firewall(String, u16),
}

impl Source {
    /// The local UDP port.
    pub fn port(&self) -> u16 {
        match self {
            Source::Port(p) | Source::Multicast(_, p) | Source::Firewall(_, p) => *p,
        }
    }
}

/// `vrpn_Tracker_DTrack NAME CONNECTION [TIME_TO_REACH_JOY [BODIES FLYSTICKS [IDS...]]] [3d] [-]`.
#[derive(Clone, Debug, PartialEq)]
pub struct DTrack {
    /// Device name (tracker, button and analog).
    pub name: String,
    /// Where frames come from.
    pub source: Source,
    /// Seconds the simulated hat of an old Flystick takes to reach ±1 (0: at once).
    pub time_to_reach_joy: f32,
    /// Fixed numbers of bodies and Flysticks, and their renumbering.
    pub fixed: Option<FixedNumbering>,
    /// Report `3d` markers as sensors after the bodies and Flysticks.
    pub markers: bool,
    /// Trace every tenth frame as a text message (`-`).
    pub tracing: bool,
}

const USAGE: &str = "name, connection (PORT, GROUP:PORT or HOST:PORT:fw), [time_to_reach_joy \
                     [bodies flysticks [ids...]]] [3d] [-]";

fn is_multicast(ip: Ipv4Addr) -> bool {
    ip.octets()[0] & 0xf0 == 0xe0
}

/// Parses a `vrpn_Tracker_DTrack` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(2, USAGE)?;
    let name = line.name(0)?;
    let source = connection(line, line.word(1)?)?;
    let mut count = line.args().len();
    let (mut markers, mut tracing) = (false, false);
    while count > 2 {
        match line.args()[count - 1] {
            "-" => tracing = true,
            "3d" => markers = true,
            _ => break,
        }
        count -= 1;
    }
    let time_to_reach_joy = if count > 2 {
        line.non_negative(2, "time_to_reach_joy")?
    } else {
        0.0
    };
    let mut fixed = None;
    if count > 3 {
        if count < 5 {
            return Err(line.err(
                ConfigErrorKind::MissingArguments,
                "the number of bodies needs the number of Flysticks after it",
            ));
        }
        let bodies = line.uint(3, "number_of_bodies", 0, 256)? as i32;
        let flysticks = line.uint(4, "number_of_flysticks", 0, 256)? as i32;
        let targets = (bodies + flysticks) as usize;
        let ids = if count > 5 {
            if count - 5 != targets {
                return Err(line.err(
                    ConfigErrorKind::MissingArguments,
                    format!(
                        "renumbering needs one id per body and Flystick ({targets}), found {}",
                        count - 5
                    ),
                ));
            }
            let mut ids = Vec::with_capacity(targets);
            for i in 0..targets {
                ids.push(line.uint(5 + i, "renumbered id", 0, 511)? as i32);
            }
            Some(ids)
        } else {
            None
        };
        fixed = Some(FixedNumbering::new(bodies, flysticks, ids.as_deref()));
    }
    Ok(Box::new(DTrack {
        name,
        source,
        time_to_reach_joy,
        fixed,
        markers,
        tracing,
    }))
}

fn connection(line: &ConfigLine<'_, '_>, text: &str) -> Result<Source, ConfigError> {
    let parts: Vec<&str> = text.split(':').filter(|p| !p.is_empty()).collect();
    let port = |p: &str| -> Result<u16, ConfigError> {
        p.parse::<u16>().ok().filter(|&p| p > 0).ok_or_else(|| {
            line.err(
                ConfigErrorKind::OutOfRange,
                format!("the UDP port must be 1 to 65535, found '{p}'"),
            )
        })
    };
    match parts.as_slice() {
        [p] => Ok(Source::Port(port(p)?)),
        [host, p] => {
            let port = port(p)?;
            match host.parse::<Ipv4Addr>() {
                Ok(ip) if is_multicast(ip) => Ok(Source::Multicast(ip, port)),
                _ => Err(line.err(
                    ConfigErrorKind::BadValue,
                    format!(
                        "'{host}' is not a multicast address (224.0.0.0 to 239.255.255.255); \
                         for frames from a controller behind a stateful firewall write \
                         {host}:{port}:fw"
                    ),
                )),
            }
        }
        [host, p, "fw"] => {
            let port = port(p)?;
            if host.parse::<Ipv4Addr>().is_ok_and(is_multicast) {
                return Err(line.err(
                    ConfigErrorKind::BadValue,
                    "a multicast address cannot be combined with :fw",
                ));
            }
            Ok(Source::Firewall(host.to_string(), port))
        }
        [_, _, other] => Err(line.err(
            ConfigErrorKind::BadValue,
            format!("the connection's suffix must be 'fw', found '{other}'"),
        )),
        _ => Err(line.err(
            ConfigErrorKind::BadValue,
            format!("the connection must be PORT, GROUP:PORT or HOST:PORT:fw, found '{text}'"),
        )),
    }
}

impl DTrack {
    /// The controller's address for the firewall message, resolved now (IPv4, as C++).
    pub fn firewall_target(&self) -> Result<Option<SocketAddr>, Error> {
        let Source::Firewall(host, _) = &self.source else {
            return Ok(None);
        };
        let resolved = (host.as_str(), FIREWALL_PORT)
            .to_socket_addrs()
            .map_err(|e| Error::io(format!("resolving the DTRACK controller {host}"), e))?
            .find(SocketAddr::is_ipv4);
        match resolved {
            Some(a) if a.ip().is_multicast() => Err(Error::Unsupported(
                "a multicast address cannot be combined with :fw",
            )),
            Some(a) => Ok(Some(a)),
            None => Err(Error::io(
                format!("resolving the DTRACK controller {host}"),
                std::io::Error::new(std::io::ErrorKind::NotFound, "no IPv4 address"),
            )),
        }
    }
}

impl DeviceSpec for DTrack {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(
            &self.name,
            &[Interface::Tracker, Interface::Button, Interface::Analog],
        )
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(super::DTrackDevice::new(self, cx.conn())?)])
    }
}
