//! The data the stages and backends exchange: the LDI (built by either backend, read by both
//! sweeps), the sweep's options, limits and output, and the files a scene names, read by the
//! host (`convshadow-io`) and handed to the stages.

pub mod files;
pub mod ldi;
pub mod sweep_io;
