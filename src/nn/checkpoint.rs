//! Policy directories (placeholder while building).
