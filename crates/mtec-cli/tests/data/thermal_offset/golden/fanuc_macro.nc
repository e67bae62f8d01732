(mtec compensate thermal-offset, model machine.json)
(state now: now.csv line 4 at 60 min, run from line 2 at 0 min)
(Z thermal drift +12.00 um, envelope weight 1: the offset moves -12.00 um)
#5223=-312.462
