//! Point-cloud file formats (PCD, PLY) as untrusted input.
