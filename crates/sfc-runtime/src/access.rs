//! Who may talk to the monitor (`docs/monitor.md`, "Connection").
//!
//! - **Host.** The WebSocket handshake must name a loopback host (`127.0.0.1`, `localhost`,
//!   `[::1]`), the address the connection came to, or a name given in the configuration: a web
//!   page that points its own host name at this machine (DNS rebinding) carries its own name
//!   and is refused.
//! - **Origin.** A browser sends the page's origin: absent (not a browser) is accepted, and so
//!   is the editor's own origin: by default a page served from this machine's loopback
//!   (`sfc edit` serves on `http://127.0.0.1:PORT`), or exactly the origins configured. Any
//!   other web page the user visits is refused, so it can neither watch nor, with a stolen
//!   token, force.
//! - **Wrong tokens** slow a client down: after each failed token its address must wait before
//!   the next try, 100 ms doubling up to 30 s; a right token clears the count, and so do ten
//!   quiet minutes.

use std::collections::HashMap;
use std::net::{IpAddr, SocketAddr};
use std::time::{Duration, Instant};

/// Which pages and host names the monitor accepts.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MonitorAccess {
    /// Exactly these origins (`http://127.0.0.1:8080`); `None`: pages served from loopback.
    pub origins: Option<Vec<String>>,
    /// Host names accepted besides loopback and the address the connection came to.
    pub hosts: Vec<String>,
}

/// The host part of a `Host` header or an origin's authority, lowercase, without port and
/// brackets.
fn host_part(authority: &str) -> String {
    let a = authority.trim();
    let host = if let Some(rest) = a.strip_prefix('[') {
        rest.split(']').next().unwrap_or("")
    } else {
        match a.rsplit_once(':') {
            Some((h, port)) if port.chars().all(|c| c.is_ascii_digit()) => h,
            _ => a,
        }
    };
    host.trim_end_matches('.').to_ascii_lowercase()
}

fn is_loopback_name(host: &str) -> bool {
    host == "localhost" || host.parse::<IpAddr>().is_ok_and(|ip| ip.is_loopback())
}

/// Checks the `Host` header of a handshake that arrived at `local`.
pub fn check_host(host: Option<&str>, local: SocketAddr, access: &MonitorAccess) -> Result<(), String> {
    let Some(h) = host else {
        return Err("the request has no Host header".into());
    };
    let name = host_part(h);
    let own = name.parse::<IpAddr>().is_ok_and(|ip| ip == local.ip());
    if is_loopback_name(&name) || own || access.hosts.iter().any(|x| x.eq_ignore_ascii_case(&name)) {
        Ok(())
    } else {
        Err(format!("the Host `{h}` is not this machine's loopback address or a configured host name"))
    }
}

/// Checks the `Origin` header of a handshake.
pub fn check_origin(origin: Option<&str>, access: &MonitorAccess) -> Result<(), String> {
    let Some(o) = origin else { return Ok(()) };
    let o = o.trim();
    let ok = match &access.origins {
        Some(list) => list.iter().any(|x| x.trim_end_matches('/').eq_ignore_ascii_case(o)),
        None => match o.split_once("://") {
            Some((scheme, authority)) => {
                matches!(scheme.to_ascii_lowercase().as_str(), "http" | "https")
                    && !authority.contains('/')
                    && is_loopback_name(&host_part(authority))
            }
            None => false,
        },
    };
    if ok {
        Ok(())
    } else {
        Err(format!("the web page at `{o}` may not use the monitor (only the editor's own origin)"))
    }
}

/// The first wait after a wrong token.
const FIRST_WAIT: Duration = Duration::from_millis(100);
/// The longest wait.
const MAX_WAIT: Duration = Duration::from_secs(30);
/// Failures are forgotten after this long without one.
const FORGET: Duration = Duration::from_secs(600);
/// Addresses remembered at most.
const MAX_CLIENTS: usize = 4096;

#[derive(Debug, Clone, Copy)]
struct Record {
    failures: u32,
    /// No token is checked before this.
    blocked_until: Instant,
    last_failure: Instant,
}

/// Failed tokens per client address.
#[derive(Debug, Default)]
pub struct Guesses {
    by_address: HashMap<IpAddr, Record>,
}

impl Guesses {
    /// Whether `ip` may try a token now; `Err` is how long it must still wait.
    pub fn may_try(&mut self, ip: IpAddr, now: Instant) -> Result<(), Duration> {
        match self.by_address.get(&ip) {
            Some(r) if now.saturating_duration_since(r.last_failure) >= FORGET => {
                self.by_address.remove(&ip);
                Ok(())
            }
            Some(r) if now < r.blocked_until => Err(r.blocked_until - now),
            _ => Ok(()),
        }
    }

    /// A wrong token from `ip`; returns how long it must now wait.
    pub fn failed(&mut self, ip: IpAddr, now: Instant) -> Duration {
        if self.by_address.len() >= MAX_CLIENTS && !self.by_address.contains_key(&ip) {
            self.by_address.retain(|_, r| now < r.blocked_until);
            if self.by_address.len() >= MAX_CLIENTS {
                // Still full of blocked addresses: the oldest failure goes.
                if let Some(oldest) = self.by_address.iter().min_by_key(|(_, r)| r.last_failure).map(|(k, _)| *k) {
                    self.by_address.remove(&oldest);
                }
            }
        }
        let r = self.by_address.entry(ip).or_insert(Record { failures: 0, blocked_until: now, last_failure: now });
        r.failures = r.failures.saturating_add(1);
        let wait = FIRST_WAIT.saturating_mul(1u32 << (r.failures - 1).min(16)).min(MAX_WAIT);
        r.blocked_until = now + wait;
        r.last_failure = now;
        wait
    }

    /// A right token from `ip`.
    pub fn succeeded(&mut self, ip: IpAddr) {
        self.by_address.remove(&ip);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hosts() {
        let local: SocketAddr = "127.0.0.1:9002".parse().unwrap();
        let a = MonitorAccess::default();
        for ok in ["127.0.0.1:9002", "localhost:9002", "LOCALHOST", "[::1]:9002", "127.1.2.3:80", "localhost.:1"] {
            assert!(check_host(Some(ok), local, &a).is_ok(), "{ok}");
        }
        for bad in ["evil.example:9002", "127.0.0.1.evil.example", "10.0.0.5:9002", ""] {
            assert!(check_host(Some(bad), local, &a).is_err(), "{bad}");
        }
        assert!(check_host(None, local, &a).is_err());
        let lan: SocketAddr = "10.0.0.5:9002".parse().unwrap();
        assert!(check_host(Some("10.0.0.5:9002"), lan, &a).is_ok());
        let named = MonitorAccess { hosts: vec!["plc1.plant".into()], ..Default::default() };
        assert!(check_host(Some("PLC1.plant:9002"), lan, &named).is_ok());
    }

    #[test]
    fn origins() {
        let a = MonitorAccess::default();
        for ok in [None, Some("http://127.0.0.1:8080"), Some("http://localhost:5173"), Some("https://[::1]:1")] {
            assert!(check_origin(ok, &a).is_ok(), "{ok:?}");
        }
        for bad in ["https://evil.example", "http://127.0.0.1.evil.example", "null", "file://", "http://10.0.0.1"] {
            assert!(check_origin(Some(bad), &a).is_err(), "{bad}");
        }
        let exact = MonitorAccess { origins: Some(vec!["http://127.0.0.1:8080".into()]), ..Default::default() };
        assert!(check_origin(Some("http://127.0.0.1:8080"), &exact).is_ok());
        assert!(check_origin(Some("http://127.0.0.1:8081"), &exact).is_err());
        assert!(check_origin(None, &exact).is_ok());
    }

    #[test]
    fn wrong_tokens_wait_longer_and_longer() {
        let mut g = Guesses::default();
        let ip: IpAddr = "127.0.0.1".parse().unwrap();
        let t0 = Instant::now();
        assert!(g.may_try(ip, t0).is_ok());
        assert_eq!(g.failed(ip, t0), Duration::from_millis(100));
        assert!(g.may_try(ip, t0 + Duration::from_millis(50)).is_err());
        assert!(g.may_try(ip, t0 + Duration::from_millis(100)).is_ok());
        assert_eq!(g.failed(ip, t0), Duration::from_millis(200));
        assert_eq!(g.failed(ip, t0), Duration::from_millis(400));
        for _ in 0..20 {
            g.failed(ip, t0);
        }
        assert_eq!(g.failed(ip, t0), MAX_WAIT);
        let other: IpAddr = "127.0.0.2".parse().unwrap();
        assert!(g.may_try(other, t0).is_ok(), "per client");
        g.succeeded(ip);
        assert!(g.may_try(ip, t0).is_ok());
        g.failed(ip, t0);
        assert!(g.may_try(ip, t0 + FORGET).is_ok());
    }
}
