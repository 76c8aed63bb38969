//! Quality metrics of synthesised maps (in progress).
