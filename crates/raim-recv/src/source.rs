//! Where a stream comes from: a file, `tcp://HOST:PORT` (an NTRIP-less
//! TCP server such as `str2str -out tcpsvr://:PORT` or a receiver's own
//! port), or `serial:PATH:BAUD` (8N1, through the `serialport` crate).

use std::io::Read;
use std::path::PathBuf;
use std::time::Duration;

/// A parsed source.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Spec {
    File(PathBuf),
    Tcp(String),
    Serial { path: String, baud: u32 },
}

/// How long one serial or TCP read waits before the stream is polled again.
const SERIAL_POLL: Duration = Duration::from_millis(200);

/// Why a source could not be opened or read.
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    #[error("bad serial source '{0}': expected serial:PATH:BAUD, e.g. serial:/dev/ttyUSB0:115200")]
    BadSerial(String),
    #[error("bad TCP source '{0}': expected tcp://HOST:PORT")]
    BadTcp(String),
    #[error("{what}: {detail}")]
    Open { what: String, detail: String },
}

impl Spec {
    /// Parse `FILE`, `tcp://HOST:PORT` or `serial:PATH:BAUD`.
    pub fn parse(s: &str) -> Result<Spec, SourceError> {
        if let Some(rest) = s.strip_prefix("tcp://") {
            let ok = rest
                .rsplit_once(':')
                .is_some_and(|(h, p)| !h.is_empty() && p.parse::<u16>().is_ok());
            return if ok {
                Ok(Spec::Tcp(rest.to_string()))
            } else {
                Err(SourceError::BadTcp(s.into()))
            };
        }
        if let Some(rest) = s.strip_prefix("serial:") {
            let (path, baud) = rest
                .rsplit_once(':')
                .ok_or_else(|| SourceError::BadSerial(s.into()))?;
            let baud: u32 = baud.parse().map_err(|_| SourceError::BadSerial(s.into()))?;
            if path.is_empty() || baud == 0 {
                return Err(SourceError::BadSerial(s.into()));
            }
            return Ok(Spec::Serial {
                path: path.into(),
                baud,
            });
        }
        Ok(Spec::File(PathBuf::from(s)))
    }

    /// A live source (TCP or serial) prints each decision as it arrives.
    pub fn is_live(&self) -> bool {
        !matches!(self, Spec::File(_))
    }

    /// Its name in messages.
    pub fn name(&self) -> String {
        match self {
            Spec::File(p) => p.display().to_string(),
            Spec::Tcp(a) => format!("tcp://{a}"),
            Spec::Serial { path, baud } => format!("serial:{path}:{baud}"),
        }
    }

    /// Open it. A serial or TCP read that times out returns
    /// `ErrorKind::TimedOut` or `WouldBlock` (the caller polls again); the end of a TCP
    /// stream or a file reads 0 bytes.
    pub fn open(&self) -> Result<Box<dyn Read + Send>, SourceError> {
        let err = |detail: String| SourceError::Open {
            what: self.name(),
            detail,
        };
        Ok(match self {
            Spec::File(p) => Box::new(std::fs::File::open(p).map_err(|e| err(e.to_string()))?),
            Spec::Tcp(a) => {
                let s = std::net::TcpStream::connect(a).map_err(|e| err(e.to_string()))?;
                // Reads wake up to let the caller see Ctrl-C and its timeouts.
                s.set_read_timeout(Some(SERIAL_POLL))
                    .map_err(|e| err(e.to_string()))?;
                Box::new(s)
            }
            Spec::Serial { path, baud } => Box::new(
                serialport::new(path, *baud)
                    .timeout(SERIAL_POLL)
                    .open()
                    .map_err(|e| err(e.to_string()))?,
            ),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse() {
        assert_eq!(
            Spec::parse("tcp://localhost:2101").unwrap(),
            Spec::Tcp("localhost:2101".into())
        );
        assert_eq!(
            Spec::parse("serial:/dev/ttyUSB0:115200").unwrap(),
            Spec::Serial {
                path: "/dev/ttyUSB0".into(),
                baud: 115_200
            }
        );
        assert_eq!(
            Spec::parse("a.rtcm3").unwrap(),
            Spec::File("a.rtcm3".into())
        );
        assert!(Spec::parse("tcp://nohost").is_err());
        assert!(Spec::parse("serial:/dev/ttyUSB0").is_err());
        assert!(Spec::parse("serial:/dev/ttyUSB0:fast").is_err());
        assert!(Spec::parse("tcp://localhost:2101").unwrap().is_live());
    }
}
