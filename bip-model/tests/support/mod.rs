pub mod errors;
pub mod random_system;
