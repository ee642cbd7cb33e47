# Scalability (paper Fig. 13): Nnz% and mean linearly implicit Euler step time vs DOFs.
# Regenerate: gnuplot validation/scaling.gp   (from the repository root; data from
# bench/study_scaling > validation/scaling.dat, see docs/validation.md)
set terminal pngcairo size 1100,480 font ",11"
set output "validation/scaling.png"
set multiplot layout 1,2 title "Beams of unit cubes (beams/cubes/cube1..cube100), quadratic, alpha 0.501"
set grid
set logscale x
set xlabel "degrees of freedom"
set ylabel "non-zeros of the system matrix, %"
set yrange [0:105]
plot "validation/scaling.dat" using 4:6 with linespoints pt 7 lc rgb "#1f77b4" notitle
set logscale xy
set yrange [*:*]
set ylabel "seconds"
set key top left
# least-squares fit on log-log axes over the largest 7 models (>= 2000 dofs), as bench/study_scaling (the exponent is printed in the data file)
lf(x) = a + p * x
a = -10; p = 1
set fit quiet logfile "/dev/null"
fit [log(2000):*] lf(x) "validation/scaling.dat" using (log($4)):(log($7)) via a, p
plot "validation/scaling.dat" using 4:7 with linespoints pt 7 lc rgb "#d62728" title "step (mean)", \
     "validation/scaling.dat" using 4:8 with linespoints pt 6 lc rgb "#ff7f0e" title "factorization", \
     exp(a) * x**p with lines dt 2 lc rgb "black" title sprintf("fit: dofs^{%.2f}", p), \
     exp(a) * 2000**p * (x / 2000.0)**1.5 with lines dt 3 lc rgb "#7f7f7f" title "dofs^{1.5}"
unset multiplot
