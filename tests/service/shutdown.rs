//! `enact-hub serve` stopped by SIGINT or SIGTERM: it stops taking connections at once, answers
//! the request in flight in full, and then exits 0.

use std::time::{Duration, Instant};

use enact_hub::core::credentials::Role;
use serde_json::Value;
use tokio::io::{AsyncBufReadExt, AsyncReadExt, AsyncWriteExt, BufReader};
use tokio::net::TcpStream;

use crate::helpers::*;
use crate::instances::Instance;

/// Reads a response head (status line and headers, up to the blank line): its status and its
/// `Content-Length`, failing after ten seconds.
async fn response_head(reader: &mut BufReader<TcpStream>) -> (u16, Option<usize>) {
    let read = async {
        let mut lines = Vec::new();
        loop {
            let mut line = String::new();
            let n = reader.read_line(&mut line).await.expect("read the reply");
            assert!(n > 0, "the connection closed after {lines:?}");
            if line.trim_end().is_empty() {
                break lines;
            }
            lines.push(line.trim_end().to_owned());
        }
    };
    let lines = tokio::time::timeout(Duration::from_secs(10), read)
        .await
        .expect("a response head within 10 s");
    let status = lines[0]
        .split(' ')
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("not a status line: {lines:?}"));
    let length = lines.iter().find_map(|l| {
        let (name, value) = l.split_once(':')?;
        name.eq_ignore_ascii_case("content-length")
            .then(|| value.trim().parse().expect("a length"))
    });
    (status, length)
}

/// A submission is half uploaded (the server asked for its body with `100 Continue`, so the
/// handler runs) when `signal` arrives: the port refuses new connections while the upload is
/// still open, the rest of the body is read and answered 201 in full, and the process exits 0.
async fn the_request_in_flight_finishes_after(signal: &str) {
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let db = server.db_path();
    let mut serve = Instance::start_with(db.to_str().expect("a UTF-8 location"), &[], &[]);
    let addr = serve.base.trim_start_matches("http://").to_owned();
    let body = answers(&records, &[0]);
    let (first, rest) = body.split_at(body.len() / 2);

    let mut upload = BufReader::new(TcpStream::connect(&addr).await.expect("connect"));
    let head = format!(
        "POST /api/v1/datasets/mini/submissions?model=m HTTP/1.1\r\nHost: {addr}\r\n\
         Authorization: Bearer {token}\r\nContent-Length: {}\r\n\
         Expect: 100-continue\r\n\r\n",
        body.len()
    );
    upload
        .get_mut()
        .write_all(head.as_bytes())
        .await
        .expect("send the head");
    assert_eq!(response_head(&mut upload).await.0, 100);
    upload
        .get_mut()
        .write_all(first.as_bytes())
        .await
        .expect("send half the body");

    serve.signal(signal);
    // A connection made while the listener closes may be taken into its backlog and reset:
    // the port is closed once connecting is refused outright.
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        match TcpStream::connect(&addr).await {
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => break,
            Err(e) if e.kind() != std::io::ErrorKind::ConnectionReset => {
                panic!("connecting after {signal}: {e}")
            }
            _ => assert!(
                Instant::now() < deadline,
                "still taking connections 5 s after {signal}"
            ),
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }

    upload
        .get_mut()
        .write_all(rest.as_bytes())
        .await
        .expect("send the rest of the body");
    let (status, length) = response_head(&mut upload).await;
    let mut reply = vec![0; length.expect("a Content-Length")];
    upload
        .read_exact(&mut reply)
        .await
        .expect("the whole reply");
    let reply: Value = serde_json::from_slice(&reply).expect("a JSON reply");
    assert_eq!(status, 201, "{reply}");
    let id = reply["id"].as_i64().expect("an id");
    assert_eq!(reply["scores"]["coverage"]["missing"], 0, "{reply}");
    let stored = count(
        &server.pool,
        &format!("SELECT count(*) FROM submission_items WHERE submission = {id}"),
    )
    .await;
    assert_eq!(stored, records.len() as i64);

    let exit = serve.exit_within(Duration::from_secs(10)).await;
    assert_eq!(exit.code(), Some(0), "after {signal}: {exit}");
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sigint_lets_the_request_in_flight_finish_and_exits_0() {
    the_request_in_flight_finishes_after("INT").await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sigterm_lets_the_request_in_flight_finish_and_exits_0() {
    the_request_in_flight_finishes_after("TERM").await;
}
