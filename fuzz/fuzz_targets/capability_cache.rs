//! A cache file of motion graphs and cost maps, any bytes: read as a whole file (header,
//! checksum, payload) and, since a fuzzer cannot forge a SHA-256, as a payload alone,
//! which is where decoding and the checks that the parts fit together run. Never a
//! panic; whatever decodes is safe to use (every index in range).
#![no_main]

use fieldhouse_core::costmap::cache;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = cache::decode(data);
    if let Ok(cached) = cache::decode_payload(data) {
        for node in 0..cached.graph.node_count() as u32 {
            let _ = cached.graph.pose(node);
            for e in cached.graph.out_edges(node) {
                let _ = cached.graph.edges[e];
            }
        }
        for map in &cached.maps {
            for path in &map.paths {
                for &e in path {
                    let _ = cached.graph.edges[e as usize];
                }
            }
        }
    }
});
