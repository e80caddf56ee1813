//! PCD (ascii, binary) and PLY (ascii, binary LE) uploads: `read_cloud_file` must return a cloud
//! or a field error, never panic, and never allocate from an unchecked header count. Non-finite
//! coordinates may pass (the facade's validation names them); NaN points are dropped.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(cloud) = graspd_core::cloud::io::read_cloud_file(data) {
        assert!(cloud.points.iter().all(|p| !p.iter().any(|v| v.is_nan())));
        if let Some(normals) = &cloud.normals {
            assert_eq!(normals.len(), cloud.points.len());
        }
    }
});
