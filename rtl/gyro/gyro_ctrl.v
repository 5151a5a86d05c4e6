// gyro_ctrl: reads the yaw rate (Z axis) of a TDK InvenSense ICM-42688-P over SPI and sums it per
// window (see docs/GYRO.md for the part, the registers and the datasheet sections followed).
//
// Start-up (each step one SPI transaction of spi_master, mode 0, address byte first, bit 7 = read):
//   1. DEVICE_CONFIG (0x11) <= 0x01: soft reset; wait RESET_WAIT_US.
//   2. read WHO_AM_I (0x75); not 0x47: a wrong-ID fault, wait RETRY_US and start again at 1
//      (gyro_id_fault_o is high while it waits).
//   3. PWR_MGMT0 (0x4E) <= 0x0C (gyro in low-noise mode, accel off); wait PWR_WAIT_US (the part
//      takes no register write for 200 us after a mode change).
//   4. GYRO_CONFIG0 (0x4F) <= {GYRO_FS_SEL, 0, GYRO_ODR} from FS_DPS and ODR_HZ; wait START_WAIT_US
//      (gyro start-up time).
// Running (gyro_running_o high): read INT_STATUS (0x2D, clear on read) until DATA_RDY_INT (bit 3),
// then read GYRO_DATA_Z1, GYRO_DATA_Z0 (0x29, 0x2A, one burst with auto-increment: big-endian
// signed 16 bit) and hand the sample to gyro_accum. No data-ready for DRDY_TIMEOUT_US: a timeout
// fault and the whole start-up again (a part that lost power comes back in reset).
//
// Samples rejected (counted as faults, never summed): 0x8000 (the part's "no valid data" value),
// and every sample from the STUCK_N-th of a run of identical values on. Faults: gyro_flags_o bit 0
// wrong ID, 1 data-ready timeout, 2 stuck value, 3 invalid (0x8000), 4 a sample dropped because
// the window's count was full; gyro_fault_count_o counts the fault events (saturating).
//
// Windows: on tick_i (the same window tick as the encoders) the sum, count and flags of the window
// are latched into gyro_sum_o / gyro_count_o / gyro_flags_o, gyro_valid_o pulses, and the next
// window starts; a sample that arrives in the tick cycle is handed over one cycle later and so
// belongs to the new window (gyro_accum). tick_i must be a one-cycle pulse.
//
// Timing: the waits are counted in units of 100 us (a prescaler of CLK_HZ / 10000 cycles restarted
// at each wait), each wait rounded up to whole units.
`resetall
`timescale 1ns / 1ps
`default_nettype none

`include "omniloc_regs.vh"

module gyro_ctrl #(
    parameter integer CLK_HZ = `OMNILOC_BOARD_CLOCK_HZ,  // clk_i frequency
    parameter integer SCLK_HZ = `OMNILOC_GYRO_SCLK_HZ,   // SPI clock (the part allows up to 24 MHz)
    parameter integer ODR_HZ = `OMNILOC_GYRO_ODR_HZ,     // gyro output data rate: 1000..32000 (table)
    parameter integer FS_DPS = `OMNILOC_GYRO_FS_DPS,     // gyro full scale: 2000, 1000, 500, 250, 125, 62, 31, 15
    parameter integer COUNT_W = 8,               // bits of the per-window sample count
    parameter integer FCNT_W = 8,                // bits of the saturating fault counter
    parameter integer STUCK_N = 64,              // identical samples in a row that make a stuck value
    parameter integer RESET_WAIT_US = 1000,      // after the soft reset
    parameter integer PWR_WAIT_US = 200,         // after PWR_MGMT0
    parameter integer START_WAIT_US = 30000,     // after GYRO_CONFIG0: gyro start-up
    parameter integer DRDY_TIMEOUT_US = 5000,    // no data-ready this long: timeout fault
    parameter integer RETRY_US = 100000          // wait after a wrong WHO_AM_I
) (
    input  wire                       clk_i,
    input  wire                       rst_i,
    input  wire                       tick_i,
    output wire                       spi_sclk_o,
    output wire                       spi_mosi_o,
    input  wire                       spi_miso_i,
    output wire                       spi_cs_n_o,
    output wire signed [15+COUNT_W:0] gyro_sum_o,
    output wire [COUNT_W-1:0]         gyro_count_o,
    output wire [4:0]                 gyro_flags_o,
    output wire                       gyro_valid_o,
    output wire [FCNT_W-1:0]          gyro_fault_count_o,
    output wire                       gyro_running_o,
    output wire                       gyro_id_fault_o
);

// ---- Register map, user bank 0 (DS-000347 "Register map"; docs/GYRO.md) ----
localparam [7:0] REG_DEVICE_CONFIG = 8'h11;
localparam [7:0] REG_GYRO_DATA_Z1 = 8'h29;
localparam [7:0] REG_INT_STATUS = 8'h2D;
localparam [7:0] REG_PWR_MGMT0 = 8'h4E;
localparam [7:0] REG_GYRO_CONFIG0 = 8'h4F;
localparam [7:0] REG_WHO_AM_I = 8'h75;
localparam [7:0] WHO_AM_I_VALUE = 8'h47;
localparam [7:0] SOFT_RESET = 8'h01;          // DEVICE_CONFIG.SOFT_RESET_CONFIG
localparam [7:0] PWR_GYRO_LN = 8'h0C;         // PWR_MGMT0.GYRO_MODE = 11 (low noise)
localparam integer DATA_RDY_BIT = 3;          // INT_STATUS.DATA_RDY_INT
localparam [7:0] READ = 8'h80;

localparam [2:0] FS_SEL = FS_DPS >= 2000 ? 3'd0 : FS_DPS >= 1000 ? 3'd1 : FS_DPS >= 500 ? 3'd2 :
                          FS_DPS >= 250 ? 3'd3 : FS_DPS >= 125 ? 3'd4 : FS_DPS >= 62 ? 3'd5 :
                          FS_DPS >= 31 ? 3'd6 : 3'd7;
localparam [3:0] ODR_SEL = ODR_HZ == 32000 ? 4'd1 : ODR_HZ == 16000 ? 4'd2 : ODR_HZ == 8000 ? 4'd3 :
                           ODR_HZ == 4000 ? 4'd4 : ODR_HZ == 2000 ? 4'd5 : ODR_HZ == 1000 ? 4'd6 :
                           4'd0;
localparam [7:0] GYRO_CONFIG0_VALUE = {FS_SEL, 1'b0, ODR_SEL};

generate
    if (ODR_SEL == 4'd0) begin : bad_odr_hz
        // Only the rates of the table, all >= 1 kHz; anything else stops the elaboration.
        bad_parameter_ODR_HZ_must_be_1000_2000_4000_8000_16000_or_32000 odr_hz_error();
    end
    if (STUCK_N < 2) begin : bad_stuck_n
        bad_parameter_STUCK_N_must_be_at_least_2 stuck_n_error();
    end
endgenerate

// ---- Waits in units of 100 us ----
localparam integer UNIT_US = 100;
localparam integer PRESCALE_RAW = CLK_HZ / (1_000_000 / UNIT_US);
localparam integer PRESCALE = PRESCALE_RAW < 1 ? 1 : PRESCALE_RAW;
localparam integer PRE_W = PRESCALE > 1 ? $clog2(PRESCALE) : 1;
localparam integer PRESCALE_M1 = PRESCALE - 1;
localparam integer U_RESET = (RESET_WAIT_US + UNIT_US - 1) / UNIT_US;
localparam integer U_PWR = (PWR_WAIT_US + UNIT_US - 1) / UNIT_US;
localparam integer U_START = (START_WAIT_US + UNIT_US - 1) / UNIT_US;
localparam integer U_TIMEOUT = (DRDY_TIMEOUT_US + UNIT_US - 1) / UNIT_US;
localparam integer U_RETRY = (RETRY_US + UNIT_US - 1) / UNIT_US;
localparam integer U_MAX_A = U_RESET > U_PWR ? U_RESET : U_PWR;
localparam integer U_MAX_B = U_START > U_TIMEOUT ? U_START : U_TIMEOUT;
localparam integer U_MAX_C = U_MAX_A > U_MAX_B ? U_MAX_A : U_MAX_B;
localparam integer U_MAX = U_MAX_C > U_RETRY ? U_MAX_C : U_RETRY;
localparam integer TIM_W = $clog2(U_MAX + 1);
localparam integer RUN_W = $clog2(STUCK_N);
localparam integer STUCK_LAST = STUCK_N - 2;    // run_q value at which the next repeat is stuck
localparam integer RUN_MAX = STUCK_N - 1;

// ---- States: the transaction states end in the following wait state ----
localparam [3:0] S_RST    = 4'd0;   // write DEVICE_CONFIG
localparam [3:0] S_WRST   = 4'd1;
localparam [3:0] S_ID     = 4'd2;   // read WHO_AM_I
localparam [3:0] S_RETRY  = 4'd3;   // wrong ID: wait, then start again
localparam [3:0] S_PWR    = 4'd4;   // write PWR_MGMT0
localparam [3:0] S_WPWR   = 4'd5;
localparam [3:0] S_CFG    = 4'd6;   // write GYRO_CONFIG0
localparam [3:0] S_WSTART = 4'd7;
localparam [3:0] S_POLL   = 4'd8;   // read INT_STATUS
localparam [3:0] S_DATA   = 4'd9;   // read GYRO_DATA_Z1, GYRO_DATA_Z0

reg [3:0]       state_d, state_q;
reg [PRE_W-1:0] pre_q;
reg [TIM_W-1:0] tim_q;
reg             load;            // (combinational) restart the wait with load_units
reg [TIM_W-1:0] load_units;
reg [1:0]       byte_q;          // byte of the current transaction
reg             wait_q;          // a byte is in flight in spi_master
reg [7:0]       z1_q;            // GYRO_DATA_Z1 of the current burst
reg [15:0]      prev_q;          // the previous sample
reg [RUN_W-1:0] run_q;           // how many times in a row prev_q repeated its predecessor
reg [3:0]       fault;           // (combinational) fault pulses
reg [3:0]       fault_q;         // ... registered on their way to gyro_accum (off the state decode's path)

wire spi_busy, spi_done;
wire [7:0] spi_rx;
reg  [7:0] tx;
wire is_xfer = state_q == S_RST || state_q == S_ID || state_q == S_PWR || state_q == S_CFG
               || state_q == S_POLL || state_q == S_DATA;
wire [1:0] last_byte = state_q == S_DATA ? 2'd2 : 2'd1;
wire spi_start = is_xfer && !wait_q && !spi_busy;
wire txn_end = spi_done && byte_q == last_byte;   // the last byte of a transaction arrived
wire tim_zero = tim_q == {TIM_W{1'b0}};

// The sample of a completed data burst, registered with its two comparisons (stage S: the 16-bit
// compares end in flip-flops, off the path into gyro_accum), then judged in the next cycle
// (stage C): stuck from the run length, invalid, or handed to gyro_accum.
wire [15:0] sample = {z1_q, spi_rx};
wire sample_end = txn_end && state_q == S_DATA;
reg  [15:0] smp_q;               // stage S: the sample
reg         smp_v_q;             // stage S holds a new sample this cycle
reg         invalid_q, same_q;   // stage S: it is 0x8000; it equals its predecessor
reg         run_long_q;          // run_q >= STUCK_LAST, kept beside run_q (no compare on the path)
wire stuck = same_q && run_long_q;
// A good sample goes to gyro_accum in stage C, or one cycle later if that cycle is a tick (pend_q):
// smp_q holds until the next burst ends, microseconds later.
wire [RUN_W-1:0] run_next = !same_q ? {RUN_W{1'b0}} : run_q == RUN_MAX[RUN_W-1:0] ? run_q : run_q + 1'b1;
reg  pend_q;
wire accum_taken;
wire sample_ok = (smp_v_q && !invalid_q && !stuck) || pend_q;

always @(*) begin
    case (state_q)
        S_RST:   tx = byte_q == 2'd0 ? REG_DEVICE_CONFIG : SOFT_RESET;
        S_ID:    tx = byte_q == 2'd0 ? (READ | REG_WHO_AM_I) : 8'h00;
        S_PWR:   tx = byte_q == 2'd0 ? REG_PWR_MGMT0 : PWR_GYRO_LN;
        S_CFG:   tx = byte_q == 2'd0 ? REG_GYRO_CONFIG0 : GYRO_CONFIG0_VALUE;
        S_POLL:  tx = byte_q == 2'd0 ? (READ | REG_INT_STATUS) : 8'h00;
        default: tx = byte_q == 2'd0 ? (READ | REG_GYRO_DATA_Z1) : 8'h00;   // S_DATA
    endcase
end

always @(*) begin
    state_d = state_q;
    load = 1'b0;
    load_units = U_TIMEOUT[TIM_W-1:0];
    fault = 4'd0;
    case (state_q)
        S_RST: if (txn_end) begin
            state_d = S_WRST;
            load = 1'b1;
            load_units = U_RESET[TIM_W-1:0];
        end
        S_WRST: if (tim_zero) state_d = S_ID;
        S_ID: if (txn_end) begin
            load = 1'b1;
            if (spi_rx == WHO_AM_I_VALUE) begin
                state_d = S_PWR;
                load_units = U_PWR[TIM_W-1:0];
            end else begin
                state_d = S_RETRY;
                load_units = U_RETRY[TIM_W-1:0];
                fault[0] = 1'b1;
            end
        end
        S_RETRY: if (tim_zero) state_d = S_RST;
        S_PWR: if (txn_end) begin
            state_d = S_WPWR;
            load = 1'b1;
            load_units = U_PWR[TIM_W-1:0];
        end
        S_WPWR: if (tim_zero) state_d = S_CFG;
        S_CFG: if (txn_end) begin
            state_d = S_WSTART;
            load = 1'b1;
            load_units = U_START[TIM_W-1:0];
        end
        S_WSTART: if (tim_zero) begin
            state_d = S_POLL;
            load = 1'b1;
        end
        S_POLL: if (txn_end) begin
            if (spi_rx[DATA_RDY_BIT]) begin
                state_d = S_DATA;
                load = 1'b1;
            end else if (tim_zero) begin
                state_d = S_RST;
                fault[1] = 1'b1;
            end
        end
        S_DATA: if (txn_end) state_d = S_POLL;
        default: state_d = S_RST;
    endcase
    fault[2] = smp_v_q && !invalid_q && stuck;
    fault[3] = smp_v_q && invalid_q;
end

always @(posedge clk_i) begin
    if (rst_i) begin
        state_q <= S_RST;
        pre_q <= PRESCALE_M1[PRE_W-1:0];
        tim_q <= {TIM_W{1'b0}};
        byte_q <= 2'd0;
        wait_q <= 1'b0;
        run_q <= {RUN_W{1'b0}};
        run_long_q <= 1'b0;
        pend_q <= 1'b0;
        prev_q <= 16'd0;
        smp_v_q <= 1'b0;
        fault_q <= 4'd0;
    end else begin
        fault_q <= fault;
        pend_q <= sample_ok && !accum_taken;
        state_q <= state_d;
        if (load) begin
            pre_q <= PRESCALE_M1[PRE_W-1:0];
            tim_q <= load_units;
        end else if (pre_q == {PRE_W{1'b0}}) begin
            pre_q <= PRESCALE_M1[PRE_W-1:0];
            if (!tim_zero) tim_q <= tim_q - 1'b1;
        end else begin
            pre_q <= pre_q - 1'b1;
        end
        if (spi_start) wait_q <= 1'b1;
        if (spi_done) begin
            wait_q <= 1'b0;
            byte_q <= txn_end ? 2'd0 : byte_q + 2'd1;
        end
        smp_v_q <= sample_end;
        if (sample_end) prev_q <= sample;
        if (smp_v_q) begin
            run_q <= run_next;
            run_long_q <= run_next >= STUCK_LAST[RUN_W-1:0];
        end
    end
end

// Pure data registers (no reset needed).
always @(posedge clk_i) begin
    if (sample_end) begin
        smp_q <= sample;
        invalid_q <= sample == 16'h8000;
        same_q <= sample == prev_q;
    end
end
always @(posedge clk_i) begin
    if (spi_done && state_q == S_DATA && byte_q == 2'd1) z1_q <= spi_rx;
end

assign gyro_running_o = state_q == S_POLL || state_q == S_DATA;
assign gyro_id_fault_o = state_q == S_RETRY;

spi_master #(
    .CLK_HZ(CLK_HZ),
    .SCLK_HZ(SCLK_HZ)
) u_spi (
    .clk_i(clk_i),
    .rst_i(rst_i),
    .start_i(spi_start),
    .tx_i(tx),
    .last_i(byte_q == last_byte),
    .busy_o(spi_busy),
    .done_o(spi_done),
    .rx_o(spi_rx),
    .sclk_o(spi_sclk_o),
    .mosi_o(spi_mosi_o),
    .miso_i(spi_miso_i),
    .cs_n_o(spi_cs_n_o)
);

gyro_accum #(
    .SAMPLE_W(16),
    .COUNT_W(COUNT_W),
    .FAULT_W(4),
    .FCNT_W(FCNT_W)
) u_accum (
    .clk_i(clk_i),
    .rst_i(rst_i),
    .tick_i(tick_i),
    .sample_valid_i(sample_ok),
    .sample_i(smp_q),
    .fault_i(fault_q),
    .sum_o(gyro_sum_o),
    .count_o(gyro_count_o),
    .flags_o(gyro_flags_o),
    .valid_o(gyro_valid_o),
    .fault_count_o(gyro_fault_count_o),
    .taken_o(accum_taken)
);

endmodule

`resetall
