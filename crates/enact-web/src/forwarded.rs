//! The client's address behind reverse proxies the operator trusts (`--trusted-proxy`).
//!
//! A request that arrives from a trusted proxy names its client in `X-Forwarded-For`; each
//! proxy appends the address it was reached from, so the list is read from the right, past
//! the trusted proxies, to the first address that is not one of them. Requests from anywhere
//! else keep their connecting address: a client cannot choose its own address by sending the
//! header (which the login rate limit depends on).

use std::net::IpAddr;
use std::str::FromStr;

use axum::http::HeaderMap;

/// One trusted address, or a network of them: `10.0.0.7`, `172.16.0.0/12`, `fd00::/8`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TrustedProxy {
    network: IpAddr,
    prefix: u8,
}

impl FromStr for TrustedProxy {
    type Err = String;

    fn from_str(text: &str) -> Result<TrustedProxy, String> {
        let text = text.trim();
        let (address, prefix) = match text.split_once('/') {
            Some((address, prefix)) => (address, Some(prefix)),
            None => (text, None),
        };
        let network: IpAddr = address
            .parse()
            .map_err(|_| format!("{text:?} is not an IP address or a network (10.0.0.0/8)"))?;
        let bits = if network.is_ipv4() { 32 } else { 128 };
        let prefix = match prefix {
            None => bits,
            Some(p) => p
                .parse::<u8>()
                .ok()
                .filter(|p| *p <= bits)
                .ok_or_else(|| format!("{text:?}: the prefix length must be 0 to {bits}"))?,
        };
        Ok(TrustedProxy { network, prefix })
    }
}

impl TrustedProxy {
    fn contains(&self, address: IpAddr) -> bool {
        // An IPv4 peer may arrive as an IPv4-mapped IPv6 address on a dual-stack socket.
        let address = match address {
            IpAddr::V6(v6) => v6.to_ipv4_mapped().map_or(address, IpAddr::V4),
            v4 => v4,
        };
        match (self.network, address) {
            (IpAddr::V4(net), IpAddr::V4(a)) => {
                let mask = u32::MAX
                    .checked_shl(32 - u32::from(self.prefix))
                    .unwrap_or(0);
                u32::from(net) & mask == u32::from(a) & mask
            }
            (IpAddr::V6(net), IpAddr::V6(a)) => {
                let mask = u128::MAX
                    .checked_shl(128 - u32::from(self.prefix))
                    .unwrap_or(0);
                u128::from(net) & mask == u128::from(a) & mask
            }
            _ => false,
        }
    }
}

/// Whether `address` is one of `trusted`.
fn is_trusted(trusted: &[TrustedProxy], address: IpAddr) -> bool {
    trusted.iter().any(|t| t.contains(address))
}

/// The client a request came from: `peer` (the connecting address), or, when `peer` is a
/// trusted proxy, the rightmost address of `X-Forwarded-For` that is not a trusted proxy. An
/// entry that is not an address stops the walk there: what lies left of it was written by
/// nobody trusted, so the last trusted hop is the client as far as is known.
pub fn client_address(
    trusted: &[TrustedProxy],
    peer: Option<IpAddr>,
    headers: &HeaderMap,
) -> Option<IpAddr> {
    let mut client = peer?;
    if !is_trusted(trusted, client) {
        return Some(client);
    }
    let hops: Vec<&str> = headers
        .get_all("x-forwarded-for")
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(','))
        .map(str::trim)
        .collect();
    for hop in hops.iter().rev() {
        let Ok(address) = hop.parse::<IpAddr>() else {
            break;
        };
        client = address;
        if !is_trusted(trusted, address) {
            break;
        }
    }
    Some(client)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn proxies(list: &[&str]) -> Vec<TrustedProxy> {
        list.iter().map(|p| p.parse().unwrap()).collect()
    }

    fn forwarded(values: &[&str]) -> HeaderMap {
        let mut headers = HeaderMap::new();
        for v in values {
            headers.append("x-forwarded-for", v.parse().unwrap());
        }
        headers
    }

    fn ip(text: &str) -> Option<IpAddr> {
        Some(text.parse().unwrap())
    }

    #[test]
    fn addresses_and_networks_parse_and_bad_ones_say_why() {
        let p: TrustedProxy = "10.0.0.0/8".parse().unwrap();
        assert!(p.contains("10.200.3.4".parse().unwrap()));
        assert!(!p.contains("11.0.0.1".parse().unwrap()));
        assert!(!p.contains("::1".parse().unwrap()));
        let one: TrustedProxy = "192.168.1.7".parse().unwrap();
        assert!(one.contains("192.168.1.7".parse().unwrap()));
        assert!(!one.contains("192.168.1.8".parse().unwrap()));
        let all: TrustedProxy = "0.0.0.0/0".parse().unwrap();
        assert!(all.contains("8.8.8.8".parse().unwrap()));
        let v6: TrustedProxy = "fd00::/8".parse().unwrap();
        assert!(v6.contains("fd12::1".parse().unwrap()));
        assert!(!v6.contains("fe80::1".parse().unwrap()));
        // A mapped IPv4 peer is its IPv4 address.
        assert!(p.contains("::ffff:10.1.2.3".parse().unwrap()));
        for bad in ["proxy", "10.0.0.0/33", "10.0.0.0/x", "::/129", ""] {
            let e = bad.parse::<TrustedProxy>().unwrap_err();
            assert!(e.contains(bad.trim()), "{e}");
        }
    }

    #[test]
    fn only_a_trusted_peer_can_name_the_client() {
        let trusted = proxies(&["127.0.0.1", "172.16.0.0/12"]);
        let headers = forwarded(&["203.0.113.9"]);
        // From the proxy: the forwarded client.
        assert_eq!(
            client_address(&trusted, ip("172.18.0.5"), &headers),
            ip("203.0.113.9")
        );
        // From anyone else, the header is ignored.
        assert_eq!(
            client_address(&trusted, ip("198.51.100.1"), &headers),
            ip("198.51.100.1")
        );
        assert_eq!(
            client_address(&[], ip("127.0.0.1"), &headers),
            ip("127.0.0.1")
        );
        // No header: the proxy itself.
        assert_eq!(
            client_address(&trusted, ip("127.0.0.1"), &HeaderMap::new()),
            ip("127.0.0.1")
        );
        assert_eq!(client_address(&trusted, None, &headers), None);
    }

    #[test]
    fn the_list_is_read_from_the_right_past_trusted_hops_only() {
        let trusted = proxies(&["127.0.0.1", "10.0.0.0/8"]);
        // The client spoofed a first entry; the outer proxy (10.0.0.2) appended the real one.
        let headers = forwarded(&["1.2.3.4, 203.0.113.9, 10.0.0.2"]);
        assert_eq!(
            client_address(&trusted, ip("127.0.0.1"), &headers),
            ip("203.0.113.9")
        );
        // Several header lines are one list, in order.
        let headers = forwarded(&["1.2.3.4", "203.0.113.9", "10.0.0.2"]);
        assert_eq!(
            client_address(&trusted, ip("127.0.0.1"), &headers),
            ip("203.0.113.9")
        );
        // Garbage stops the walk at the last trusted hop.
        let headers = forwarded(&["203.0.113.9, garbage, 10.0.0.2"]);
        assert_eq!(
            client_address(&trusted, ip("127.0.0.1"), &headers),
            ip("10.0.0.2")
        );
        // Every hop trusted: the leftmost.
        let headers = forwarded(&["10.0.0.3, 10.0.0.2"]);
        assert_eq!(
            client_address(&trusted, ip("127.0.0.1"), &headers),
            ip("10.0.0.3")
        );
    }
}
