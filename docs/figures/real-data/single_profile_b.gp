# estlab figure; redraw with: gnuplot single_profile_b.gp (in this folder)
# data: single_profile_b.dat
do for [fmt in "png svg"] {
  if (fmt eq "png") {
    set terminal pngcairo noenhanced size 800,500
  } else {
    set terminal svg noenhanced size 800,500 dynamic
  }
  set output 'single_profile_b.'.fmt
  reset
  set grid
  set key outside right top
  set title 'profile likelihood of b'
  set key inside top center
  set format x '%.6g'
  set xtics rotate by -30
  set xlabel 'b'
  set ylabel 'NLL - NLL(optimum)'
  set arrow from first 0.055517369047481245, graph 0 to first 0.055517369047481245, graph 1 nohead dt 2
  plot 'single_profile_b.dat' using 1:2 with linespoints pt 7 title 'profile', 1.920729410347062 with lines dt 3 title '95 % (chi2_1 / 2 = 1.92)'
  set output
}
