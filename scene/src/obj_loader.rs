//! OBJ/MTL loading.
