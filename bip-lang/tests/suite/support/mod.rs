pub mod errors;
pub mod graphs;
