//! (to be written: see the issue for the curve module)
