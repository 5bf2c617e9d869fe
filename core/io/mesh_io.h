// Moved: the readers and writers are public API now. Kept for code written before the move.
#pragma once
#include "vdbwrap/io.h"
