// The batch corrector (windowed incremental pass + global refinement); see corrector.h.
