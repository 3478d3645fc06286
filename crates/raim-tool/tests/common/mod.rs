//! Helpers shared by the CLI tests.

use std::io::Write;
use std::net::TcpListener;
use std::time::Duration;

/// Serve `bytes` on a local TCP port in chunks, then close; returns the
/// address.
pub fn serve(bytes: Vec<u8>, chunk: usize, pause: Duration, hold: Duration) -> String {
    let l = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = l.local_addr().unwrap().to_string();
    std::thread::spawn(move || {
        if let Ok((mut s, _)) = l.accept() {
            for c in bytes.chunks(chunk) {
                if s.write_all(c).is_err() {
                    return;
                }
                std::thread::sleep(pause);
            }
            std::thread::sleep(hold);
        }
    });
    addr
}
