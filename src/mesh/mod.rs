//! (to be written: see the issue for the mesh module)
