pub mod bench;
pub mod demo;
pub mod info;
pub mod pictures;
pub mod progress;
pub mod reconstruct;
pub mod render;
pub mod synth;
