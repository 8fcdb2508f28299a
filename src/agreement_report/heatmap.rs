//! The comparison heatmap.
