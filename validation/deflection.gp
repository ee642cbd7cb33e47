# Deflection study (paper Fig. 10): SEM tip deflection as % of the converged FEM figure.
# Regenerate: gnuplot validation/deflection.gp   (from the repository root; data from
# bench/study_deflection, see docs/validation.md)
set terminal pngcairo size 900,560 font ",11"
set output "validation/deflection.png"
set title "Cantilever 5 x 1 x 1 m: SEM tip deflection / FEM (CalculiX C3D10, NLGEOM); generated beams 1..30 sections"
set xlabel "degrees of freedom (3 x control points)"
set ylabel "tip deflection, % of FEM"
set key bottom right
set grid
set yrange [0:140]
f(x) = 100
g(x) = 90
plot f(x) with lines dt 2 lc rgb "black" title "FEM", \
     g(x) with lines dt 3 lw 1.5 lc rgb "#555555" title "FEM - 10 %", \
     "validation/deflection_g1e7.dat" using (strcol(1) ne "generated" ? $4 : 1/0):6 with linespoints pt 7 lc rgb "#d62728" title "b1..b10 files, gamma 1e7 (authors')", \
     "validation/deflection_g1e7.dat" using (strcol(1) eq "generated" ? $4 : 1/0):6 with linespoints pt 6 lc rgb "#ff7f0e" title "generated beams, gamma 1e7", \
     "validation/deflection_g1e9.dat" using (strcol(1) eq "generated" ? $4 : 1/0):6 with linespoints pt 4 lc rgb "#1f77b4" title "generated beams, gamma 1e9", \
     "validation/deflection_g1e10.dat" using (strcol(1) eq "generated" ? $4 : 1/0):6 with linespoints pt 12 lc rgb "#9467bd" title "generated beams, gamma 1e10", \
     "validation/deflection_default.dat" using (strcol(1) ne "generated" ? $4 : 1/0):6 with linespoints pt 9 lc rgb "#2ca02c" title "b1..b10 files, default gamma (1000 E / L = 1.9e8)", \
     "validation/deflection_default.dat" using (strcol(1) eq "generated" ? $4 : 1/0):6 with linespoints pt 8 lc rgb "#98df8a" title "generated beams, default gamma"
