//! Mask statistics (placeholder while building).
