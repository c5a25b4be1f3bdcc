//! Masked networks in candle (METHOD.md section 2): knows nothing of the simulator.
