//! The interactive viewer.
