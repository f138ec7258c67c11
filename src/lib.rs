pub mod fielding;
pub mod perception;
pub mod physics;
