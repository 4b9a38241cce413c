//! Errors of the scene pipeline, each naming the file and what is wrong with it.
