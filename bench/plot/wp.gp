# Work-precision diagram settings shared by every problem (bench/plot/report.py writes the
# per-problem data and plot command, then loads this file first). Error against CPU time,
# log-log: down and to the left is better.
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set xlabel "CPU time per run (s)"
set ylabel "max position error over the run (m)"
set grid xtics ytics mxtics mytics lc rgb "#dddddd" lw 1
set key outside right top vertical Left reverse spacing 1.05 font ",9"
set border lw 1
# Colours by stepper, dash by formulation: Appell minimal solid, projected dashed,
# the hand-reduced ODE ("limit") dotted; peers thick.
set linetype 1 lc rgb "#1f77b4" lw 1.5 pt 7 ps 0.6
set linetype 2 lc rgb "#ff7f0e" lw 1.5 pt 7 ps 0.6
set linetype 3 lc rgb "#2ca02c" lw 1.5 pt 7 ps 0.6
set linetype 4 lc rgb "#d62728" lw 1.5 pt 7 ps 0.6
set linetype 5 lc rgb "#9467bd" lw 1.5 pt 7 ps 0.6
set linetype 6 lc rgb "#8c564b" lw 1.5 pt 7 ps 0.6
set linetype 7 lc rgb "#e377c2" lw 1.5 pt 7 ps 0.6
set linetype 8 lc rgb "#17becf" lw 1.5 pt 7 ps 0.6
set linetype 9 lc rgb "#000000" lw 1.5 pt 7 ps 0.6
