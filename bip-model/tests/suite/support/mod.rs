pub mod random_system;
