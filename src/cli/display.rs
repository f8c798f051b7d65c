//! `--display-server HOST:PORT`: the image as it renders, sent to the tev viewer over its TCP
//! protocol (pbrt-v4's `--display-server`), through the `tev_client` crate. A viewer that
//! cannot be reached, or that goes away, costs a warning, never the render.

use crate::geometry::Spectrum;
use std::net::{TcpStream, ToSocketAddrs};
use std::sync::Mutex;
use std::time::Duration;
use tev_client::{PacketCreateImage, PacketUpdateImage, TevClient};

/// How long to wait for the viewer to accept the connection.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(2);

/// Values per update packet at most: tev reads a packet whole, so a large image goes in bands.
const VALUES_PER_PACKET: usize = 1 << 20;

/// A connection to tev showing one image.
pub struct Display {
    client: Mutex<Option<TevClient>>,
    name: String,
    width: usize,
    height: usize,
}

impl Display {
    /// Connects to tev at `address` and creates a black `width` x `height` image called
    /// `name` (R, G, B); a warning, and `None`, when tev cannot be reached.
    pub fn connect(address: &str, name: &str, width: usize, height: usize) -> Option<Display> {
        let connect = || -> std::io::Result<TcpStream> {
            let mut last = None;
            for a in address.to_socket_addrs()? {
                match TcpStream::connect_timeout(&a, CONNECT_TIMEOUT) {
                    Ok(s) => return Ok(s),
                    Err(e) => last = Some(e),
                }
            }
            Err(last.unwrap_or_else(|| std::io::Error::other("no address")))
        };
        let stream = match connect() {
            Ok(s) => s,
            Err(e) => {
                eprintln!(
                    "warning: --display-server {address}: cannot reach tev ({e}); rendering \
                     without the display"
                );
                return None;
            }
        };
        let _ = stream.set_nodelay(true);
        let display = Display {
            client: Mutex::new(Some(TevClient::wrap(stream))),
            // tev's strings end at a NUL.
            name: name.replace('\0', ""),
            width,
            height,
        };
        display.send(|client| {
            client.send(PacketCreateImage {
                image_name: &display.name,
                grab_focus: true,
                width: width as u32,
                height: height as u32,
                channel_names: &["R", "G", "B"],
            })
        });
        Some(display)
    }

    /// Shows `pixels` (row-major, the image's size), in bands of rows.
    pub fn show(&self, pixels: &[Spectrum]) {
        if pixels.len() != self.width * self.height || pixels.is_empty() {
            return;
        }
        let rows_per_band = (VALUES_PER_PACKET / (3 * self.width)).max(1);
        for y in (0..self.height).step_by(rows_per_band) {
            let rows = rows_per_band.min(self.height - y);
            let band = &pixels[y * self.width..(y + rows) * self.width];
            let data: Vec<f32> = band.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
            let sent = self.send(|client| {
                client.send(PacketUpdateImage {
                    image_name: &self.name,
                    grab_focus: false,
                    channel_names: &["R", "G", "B"],
                    channel_offsets: &[0, 1, 2],
                    channel_strides: &[3, 3, 3],
                    x: 0,
                    y: y as u32,
                    width: self.width as u32,
                    height: rows as u32,
                    data: &data,
                })
            });
            if !sent {
                return;
            }
        }
    }

    /// Sends with the client, if still connected; on an error, warns and drops it.
    fn send(&self, f: impl FnOnce(&mut TevClient) -> std::io::Result<()>) -> bool {
        let mut guard = self.client.lock().unwrap_or_else(|e| e.into_inner());
        let Some(client) = guard.as_mut() else {
            return false;
        };
        if let Err(e) = f(client) {
            eprintln!("warning: --display-server: tev went away ({e}); rendering on without it");
            *guard = None;
            return false;
        }
        true
    }
}
