//! (to be written: see the issue for the surface module)
