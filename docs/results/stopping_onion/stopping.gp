# Written by hbirl; run `gnuplot /tmp/re/stopping.gp` to redraw.
$curve << EOD
1 0 0.323889
2 0.983333 0.986773
3 0.983333 0.986714
4 1 1
5 1 1
6 1 1
7 1 1
8 1 1
9 1 1
10 1 1
EOD
$stop0 << EOD
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
6 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
EOD
$stop1 << EOD
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
6 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
4 1
EOD
set terminal pngcairo size 1000,900 noenhanced font 'sans,11'
set output '/tmp/re/stopping.png'
set multiplot layout 2,1
set grid
set key bottom right
set xlabel 'demonstrations seen'
set yrange [0:1.05]
set title 'The onion figure''s runs (10 sorts from frames, the labeller''s eta) while watched: share right and mean confidence'
plot $curve using 1:2 with linespoints lw 2 pt 7 lc rgb '#1b9e77' title 'share right (tasks with >= n demonstrations)', $curve using 1:3 with linespoints lw 2 pt 5 lc rgb '#7570b3' title 'mean confidence'
set title 'Where the rule stopped (3 in a row): demonstrations at the stop'
set ylabel 'tasks'
set yrange [0:*]
set style fill solid 0.6
set boxwidth 0.4
set key top right
plot $stop0 using ($1 + 0):(1) smooth frequency with boxes lc rgb '#d95f02' title 'p = 0.90', $stop1 using ($1 + 0.4):(1) smooth frequency with boxes lc rgb '#e7298a' title 'p = 0.95'
unset multiplot
set terminal svg size 1000,900 noenhanced font 'sans,11' background rgb 'white'
set output '/tmp/re/stopping.svg'
set multiplot layout 2,1
set grid
set key bottom right
set xlabel 'demonstrations seen'
set yrange [0:1.05]
set title 'The onion figure''s runs (10 sorts from frames, the labeller''s eta) while watched: share right and mean confidence'
plot $curve using 1:2 with linespoints lw 2 pt 7 lc rgb '#1b9e77' title 'share right (tasks with >= n demonstrations)', $curve using 1:3 with linespoints lw 2 pt 5 lc rgb '#7570b3' title 'mean confidence'
set title 'Where the rule stopped (3 in a row): demonstrations at the stop'
set ylabel 'tasks'
set yrange [0:*]
set style fill solid 0.6
set boxwidth 0.4
set key top right
plot $stop0 using ($1 + 0):(1) smooth frequency with boxes lc rgb '#d95f02' title 'p = 0.90', $stop1 using ($1 + 0.4):(1) smooth frequency with boxes lc rgb '#e7298a' title 'p = 0.95'
unset multiplot
unset output
